"""The Python API: load a model, compile it, run its analysis.

    model = casmech.load("models/me751_pendulum.yaml")
    functions = casmech.compile(model)
    result = casmech.analyze(functions)
    names, values = casmech.results_table(functions, result)

The names are defined where they belong (schema, backends, runtime); this module is the one
entry the command line uses.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from casmech.backends import COMPILE_MODES, compile  # noqa: A004, F401
from casmech.equations.functions import SystemFunctions
from casmech.runtime.analyses import (  # noqa: F401
    ANALYSES,
    DYNAMICS_OPTIONS,
    analysis_settings,
    analyze,
    check,
)
from casmech.runtime.results import Result, table
from casmech.schema import load_model, load_model_text
from casmech.schema.resolved import ResolvedModel


def load(path: str | Path, overrides: Mapping[str, str] | None = None) -> ResolvedModel:
    """Read, validate and evaluate a model file (raises ModelError with every finding)."""
    return load_model(path, overrides=overrides)


def loads(text: str, file: str = "<string>",
          overrides: Mapping[str, str] | None = None) -> ResolvedModel:
    return load_model_text(text, file=file, overrides=overrides)


def results_table(functions: SystemFunctions, result: Result,
                  reaction_frames: str | Mapping[str, str] | None = None):
    """(column names, values): the results table of a Result. Each joint's reaction columns
    are in the frame its `reactions: {frame: ...}` names (default global); `reaction_frames`
    replaces it for every joint (global, body_i, body_j, joint) or the joints a mapping names."""
    return table(functions, result, reaction_frames)
