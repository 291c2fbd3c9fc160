"""casmech: a declarative compiler for 3D rigid multibody mechanisms on CasADi."""

from casmech.api import analyze, check, compile, load, loads, results_table
from casmech.errors import AnalysisError, CasmechError, ModelError, UsageError

__version__ = "0.1.0"
__all__ = ["analyze", "check", "compile", "load", "loads", "results_table", "AnalysisError",
           "CasmechError", "ModelError", "UsageError", "__version__"]
