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

from casmech.backends import COMPILE_MODES  # noqa: F401
from casmech.backends.rebind import CompiledModel, compiled_model
from casmech.equations.functions import SystemFunctions
from casmech.formulations import joint_space as joint_spaces
from casmech.model.lower import lower
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

JOINT_SPACE = "joint_space"  # a bundle's `derived` key of its JointSpace


def load(path: str | Path, overrides: Mapping[str, str] | None = None) -> ResolvedModel:
    """Read, validate and evaluate a model file (raises ModelError with every finding)."""
    return load_model(path, overrides=overrides)


def compile(model: ResolvedModel, mode: str = "interpreted") -> CompiledModel:  # noqa: A001
    """The model's named CasADi functions (a SystemFunctions) in `mode`: "interpreted" (SX
    functions), "compiled" (C generated, built and loaded through the cache; a model with
    parameters and up to 32 bodies gets a library that takes its numbers as an input) or
    "auto" (backends.compile). `.set(name=value)` gives them at other parameter values,
    without a build where the library takes the numbers (backends.rebind)."""
    return compiled_model(model, mode)


def loads(text: str, file: str = "<string>",
          overrides: Mapping[str, str] | None = None) -> ResolvedModel:
    return load_model_text(text, file=file, overrides=overrides)


def results_table(functions: SystemFunctions, result: Result,
                  reaction_frames: str | Mapping[str, str] | None = None):
    """(column names, values): the results table of a Result. Each joint's reaction columns
    are in the frame its `reactions: {frame: ...}` names (default global); `reaction_frames`
    replaces it for every joint (global, body_i, body_j, joint) or the joints a mapping names."""
    return table(functions, result, reaction_frames)


def joint_space(model: ResolvedModel | SystemFunctions) -> joint_spaces.JointSpace:
    """The joint-space dynamics of a model whose joints form a tree (a casmech.load or
    casmech.compile result: the latter's parameter values, after `set` too): mass matrix, bias
    forces, forward and inverse dynamics and their derivatives as CasADi Functions and NumPy
    calls (formulations.joint_space; docs/api.md#joint-space-dynamics). A compiled model keeps
    its joint space (built once per set of values)."""
    if not isinstance(model, SystemFunctions):
        return joint_spaces.joint_space(lower(model))
    if JOINT_SPACE not in model.derived:
        model.derived[JOINT_SPACE] = joint_spaces.joint_space(model.ir)
    return model.derived[JOINT_SPACE]
