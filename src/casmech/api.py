"""The Python API: load a model, compile it, run its analysis.

    model = casmech.load("models/me751_pendulum.yaml")
    functions = casmech.compile(model)
    result = casmech.analyze(functions)
    names, values = casmech.results_table(functions, result)

The names are defined where they belong (schema, backends, runtime), but for CompiledModel,
what `compile` returns; this module is the one entry the command line uses.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from dataclasses import field, fields
from functools import wraps
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING

import numpy as np

from casmech import backends
from casmech.backends import COMPILE_MODES  # noqa: F401
from casmech.core.records import record
from casmech.equations import checks
from casmech.equations.functions import SystemFunctions
from casmech.errors import UsageError
from casmech.model.lower import lower
from casmech.runtime import analyses, workspace
from casmech.runtime.analyses import (  # noqa: F401
    ANALYSES,
    DYNAMICS_OPTIONS,
    analysis_settings,
    check,
    mode_of,
)
from casmech.runtime.results import Result, table
from casmech.schema import load_model, load_model_text
from casmech.schema.resolved import ResolvedModel

if TYPE_CHECKING:
    from casmech.backends.handover import Handover
    from casmech.formulations import joint_space as joint_spaces


@record(repr=False, eq=False)
class CompiledModel(SystemFunctions):
    """What casmech.compile returns: the system functions of `model` (a SystemFunctions, which
    casmech.analyze takes) compiled in `mode`, and `set` to move them to other parameter
    values (backends.rebind, imported when called, so an interpreted run imports no code
    generation).

        pendulum = casmech.compile(casmech.load("models/estimate_pendulum.yaml"), "compiled")
        heavier = pendulum.set(m=2)              # a new CompiledModel; `pendulum` is unchanged
    """

    model: ResolvedModel | None = field(default=None, compare=False)
    requested: str = "auto"  # the mode asked of casmech.compile
    # an auto miss's: the compiled bundle analyses run on once the library built behind is
    # published (backends.handover; `running`)
    handover: Handover | None = field(default=None, compare=False, repr=False)

    @property
    def parameters(self) -> Mapping[str, float]:
        """The model's parameter values (read-only)."""
        return MappingProxyType(dict(self.model.parameters) if self.model else {})

    @property
    def dof(self) -> int:
        """Degrees of freedom: coordinates less the rank of phi_q at the file's pose (as
        `casmech check` counts them, drivers included; computed once)."""
        def count() -> int:
            bodies = self.ir.bodies
            q = np.concatenate([b.r0 for b in bodies] + [b.p0 for b in bodies] + [np.zeros(0)])
            return checks.structure(self, 0.0, q).dof

        return workspace.default(self).one("dof", count)

    @property
    def library(self) -> Path | None:
        """The folder of the parametric library the functions are bound to (None: none)."""
        if mode_of(self) == "interpreted":
            return None
        from casmech.backends import rebind

        return rebind.library(self)

    def set(self, values: Mapping[str, float | str] | None = None, /,
            **named: float | str) -> CompiledModel:
        """The model at other parameter values, as a new CompiledModel: `values` and `named`
        map parameter names to numbers or texts ("30 deg"). A parametric library is bound to
        the new values without a build; an interpreted bundle is built again; a value that
        changes the library's structure is a UsageError naming it (backends.rebind)."""
        given = {**dict(values or {}), **named}
        if not given:
            return self
        if self.model is None:
            raise UsageError("set needs the model these functions were compiled from: use "
                             "casmech.compile(model)")
        from casmech.backends import rebind

        functions, model = rebind.moved(self, self.model, given)
        later = self.handover.moved(model) if self.handover is not None else None
        return _wrap(functions, model, self.requested, later)

    def __repr__(self) -> str:
        shown = ", ".join(f"{name}={value:.6g}" for name, value in
                          list(self.parameters.items())[:6])
        more = len(self.parameters) - 6
        shown += f", ... ({more} more)" if more > 0 else ""
        how = mode_of(self) + (", parametric library" if self.library else "")
        name = self.model.name if self.model else self.ir.name
        bodies = f"{self.n_bodies} {'body' if self.n_bodies == 1 else 'bodies'}"
        joints = f"{len(self.joints)} joint{'' if len(self.joints) == 1 else 's'}"
        return (f"CompiledModel('{name}': {bodies}, {joints}, {self.dof} DOF; {how}; "
                f"parameters: {shown or 'none'})")


def _wrap(functions: SystemFunctions, model: ResolvedModel, mode: str,
          handover: Handover | None = None) -> CompiledModel:
    """The bundle as a CompiledModel (its functions shared; a new bundle, so a new workspace)."""
    return CompiledModel(**{f.name: getattr(functions, f.name) for f in fields(SystemFunctions)},
                         model=model, requested=mode, handover=handover)


def running(functions: SystemFunctions, given: workspace.Workspace | None = None
            ) -> SystemFunctions:
    """The bundle an analysis of `functions` runs on: the compiled one its handover gives once
    the library of an auto miss is built (backends.handover), else `functions` itself; with a
    caller's workspace `given` (which serves one bundle), `functions`."""
    handover = getattr(functions, "handover", None)
    if handover is None or given is not None:
        return functions
    return handover.ready() or functions


# analyze's parameters after `functions`, in order (as `analyze` reads them from args)
_PARAMETERS = tuple(inspect.signature(analyses.analyze).parameters)[1:]


def _argument(name: str, args: tuple, kwargs: dict):
    at = _PARAMETERS.index(name)
    return args[at] if len(args) > at else kwargs.get(name)


@wraps(analyses.analyze)
def analyze(functions: SystemFunctions, *args, **kwargs) -> Result:
    # a controller's run builds an interpreted bundle of its own from the functions: it stays
    if _argument("controller", args, kwargs) is None:
        functions = running(functions, _argument("workspace", args, kwargs))
    return analyses.analyze(functions, *args, **kwargs)


def load(path: str | Path, overrides: Mapping[str, str] | None = None) -> ResolvedModel:
    """Read, validate and evaluate a model file (raises ModelError with every finding)."""
    return load_model(path, overrides=overrides)


def compile(model: ResolvedModel, mode: str = "auto") -> CompiledModel:  # noqa: A001
    """The model's named CasADi functions (a SystemFunctions) in `mode`: "auto", the default
    (compiled when the cache holds the model's library, else interpreted while the library is
    built behind: backends.compile; the analyses of these functions, casmech.analyze and
    casmech.results_table, run compiled from the first one that starts after that build has
    published it: backends.handover), "interpreted" (SX functions, which symbolic work such
    as calling them on SX needs) or "compiled" (C generated, built and loaded through the
    cache; a model with parameters and up to 32 bodies gets a library that takes its numbers
    as an input). `.set(name=value)` gives them at other parameter values, without a build
    where the library takes the numbers (CompiledModel)."""
    functions, handover = backends.compile_handing_over(model, mode)
    return _wrap(functions, model, mode, handover)


def loads(text: str, file: str = "<string>",
          overrides: Mapping[str, str] | None = None) -> ResolvedModel:
    return load_model_text(text, file=file, overrides=overrides)


def results_table(functions: SystemFunctions, result: Result,
                  reaction_frames: str | Mapping[str, str] | None = None):
    """(column names, values): the results table of a Result. Each joint's reaction columns
    are in the frame its `reactions: {frame: ...}` names (default global); `reaction_frames`
    replaces it for every joint (global, body_i, body_j, joint) or the joints a mapping names."""
    return table(running(functions), result, reaction_frames)


def joint_space(model: ResolvedModel | SystemFunctions) -> joint_spaces.JointSpace:
    """The joint-space dynamics of a model whose joints form a tree (a casmech.load or
    casmech.compile result: the latter's parameter values, after `set` too): mass matrix, bias
    forces, forward and inverse dynamics and their derivatives as CasADi Functions and NumPy
    calls (formulations.joint_space; docs/api.md#joint-space-dynamics). A compiled model keeps
    its joint space (built once per set of values); one compiled with mode "compiled" has it
    compiled too, up to the bodies of a library over the model data (more: interpreted): each
    function in a library of the model's structure that every set of values shares, built into
    the cache when the function is first used (backends.joint_space_library). Under mode
    "auto" each function is compiled where the cache holds its library when first used, else
    interpreted (nothing is built); an auto miss's space is made again on the compiled bundle
    once its handover has it (`running`), looking in the cache again."""
    from casmech.equations.evaluation import WHERE_INLINE
    from casmech.formulations import joint_space as joint_spaces
    from casmech.runtime.joint_space_calls import Calls

    if not isinstance(model, SystemFunctions):
        return joint_spaces.joint_space(lower(model), Calls)
    requested = getattr(model, "requested", None)
    model = running(model)
    made = None
    if requested in ("compiled", "auto") and model.n_bodies <= WHERE_INLINE["parametric"]:
        def made():
            from casmech.backends import joint_space_library as library

            space = library.CompiledSpace(model.ir, build=requested == "compiled")
            return space.functions, Calls(space.evaluated, space.trailing)

    return workspace.default(model).one(
        "joint_space", lambda: joint_spaces.joint_space(model.ir, Calls, made))
