"""casmech: a declarative compiler for 3D rigid multibody mechanisms on CasADi."""

from __future__ import annotations

import importlib

from casmech.core.version import VERSION as __version__  # noqa: E402, F401

# public name -> module defining it; imported on first use (PEP 562), so `import casmech` and
# the command line pay only for what a command uses (docs/decisions/lazy-imports.md)
_LAZY = {
    **dict.fromkeys(("analyze", "check", "compile", "joint_space", "load", "loads",
                     "results_table"), "casmech.api"),
    **dict.fromkeys(("AnalysisError", "CasmechError", "ModelError", "UsageError"),
                    "casmech.errors"),
    "load_results": "casmech.io.frames",
    "show": "casmech.io.jupyter",
    "sweep": "casmech.study.api",
}
# subpackages and modules reachable as attributes (`casmech.api.ANALYSES`) without an import
_SUBMODULES = ("api", "backends", "cli", "core", "elements", "equations", "errors", "formulations",
               "importers", "io", "model", "numerics", "optimal", "runtime", "schema", "study")
__all__ = [*_LAZY, "__version__"]


def __getattr__(name: str):
    if name in _SUBMODULES:
        return importlib.import_module(f"casmech.{name}")  # the import binds the attribute
    if name not in _LAZY:
        raise AttributeError(f"module 'casmech' has no attribute '{name}'")
    value = getattr(importlib.import_module(_LAZY[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY, *_SUBMODULES})
