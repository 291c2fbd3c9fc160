"""Running an analysis of a system: the analyses by type, the settings a run uses (the
model's `analysis:` block with the caller's overrides, checked), and the structure check.

casmech.api re-exports `analyze`, `analysis_settings` and `check` as the public API.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Sequence
from dataclasses import replace

from casmech.equations.checks import Structure, structure
from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError, Interrupted, UsageError
from casmech.formulations import dae
from casmech.formulations.table import FORMULATIONS
from casmech.runtime import assembly, auto_formulation, solver_messages
from casmech.runtime.dynamics import run_dynamics
from casmech.runtime.events import Event
from casmech.runtime.joint_dynamics import METHODS, run_joint_dynamics, tree_of
from casmech.runtime.kinematics import output_times, run_assembly, run_prescribed_motion
from casmech.runtime.nonfinite import NonFinite
from casmech.runtime.results import Result, column_names
from casmech.schema import limits
from casmech.schema.resolved import Analysis

# dynamics options a caller may override -> their choices
DYNAMICS_OPTIONS = {"formulation": (*FORMULATIONS, "joint", "auto"),
                    "stabilization": dae.STABILIZATIONS, "method": ("auto", *METHODS)}


def _dynamics(f: SystemFunctions, s: Analysis, progress, extra_events=()) -> Result:
    """By the formulation asked for: joint coordinates (runtime.joint_dynamics) or the r-p /
    r-omega DAE (runtime.dynamics); auto: runtime.auto_formulation, which also examines a
    mechanism with loops for singular poses."""
    def joint() -> Result:
        return run_joint_dynamics(f, s.t_end, s.output_step, s.rtol, s.atol,
                                  progress=progress, method=s.options.get("method", "auto"),
                                  extra_events=extra_events)

    def other(formulation: str) -> Result:
        return run_dynamics(f, s.t_end, s.output_step, s.rtol, s.atol,
                            formulation=formulation, progress=progress,
                            stabilization=stabilization, extra_events=extra_events)

    stabilization = s.options.get("stabilization", "ggl")
    rows = len(output_times(0.0, s.t_end, s.output_step))
    return auto_formulation.run(f, tree_of(f), s.options.get("formulation", "auto"), rows,
                                joint, other)


def _runtime(name: str):
    """A runtime module imported on use (statics and modal need scipy.linalg)."""
    return importlib.import_module(f"casmech.runtime.{name}")


# analysis type -> run(functions, settings); settings is the model's `analysis:` block with the
# caller's overrides applied.
ANALYSES: dict[str, Callable[[SystemFunctions, Analysis, Callable | None], Result]] = {
    "kinematics": lambda f, s, p: run_prescribed_motion(f, s.t_end, s.output_step, s.type,
                                                        progress=p),
    "inverse_dynamics": lambda f, s, p: run_prescribed_motion(f, s.t_end, s.output_step, s.type,
                                                              progress=p),
    "assembly": lambda f, s, p: run_assembly(f, progress=p),
    "dynamics": _dynamics,
    "statics": lambda f, s, p: _runtime("statics").run_statics(f, progress=p),
    "modal": lambda f, s, p: _runtime("modal").run_modal(f, s, progress=p, dynamics=_dynamics),
}


def analyze(functions: SystemFunctions, analysis: str | None = None, t_end: float | None = None,
            output_step: float | None = None, rtol: float | None = None,
            atol: float | None = None, formulation: str | None = None,
            progress: Callable[[float], None] | None = None,
            stabilization: str | None = None, method: str | None = None,
            events: Sequence[Event] = ()) -> Result:
    """Run an analysis; the model's `analysis:` block gives what is not passed (for dynamics:
    formulation "auto", "joint", "rp" or "romega", stabilization "ggl" or "projection" of the
    DAEs, method "auto", "adams" or "bdf" of joint coordinates on a tree; docs/formulations.md).
    `progress`, when given, is called with the time of every output row as it is computed.
    The Result keeps `functions`: `result.to_dataframe()` is its results table as a DataFrame.
    `events`: runtime.events.Event declared by code, watched by dynamics besides the model's
    `events:` (Result.events, Result.events_dataframe())."""
    settings = analysis_settings(functions, analysis, t_end, output_step, rtol, atol,
                                 formulation, stabilization, method)
    if events and settings.type != "dynamics":
        raise UsageError(f"events are watched by dynamics, not by {settings.type}")
    run = ANALYSES[settings.type] if not events else (
        lambda f, s, p: _dynamics(f, s, p, tuple(events)))
    messages: list[str] = []  # the solvers' own stderr lines (runtime.solver_messages)
    try:
        with solver_messages.collected(messages) as stream:
            result = run(functions, settings, progress)
    except AnalysisError as error:  # the rows before a failure tabulate like a whole run's
        if error.partial is not None:
            error.partial.functions = functions
            error.partial.status = "interrupted" if isinstance(error, Interrupted) else "failed"
            _keep_messages(error.partial, messages, stream.count)
        if isinstance(error, NonFinite):  # the results column and the elements, by name
            error.explain(functions)
        raise
    _keep_messages(result, messages, stream.count)
    result.metadata.update(analysis=settings.type, mode=mode_of(functions))
    result.functions = functions
    return result


def mode_of(functions: SystemFunctions) -> str:
    """"compiled" or "interpreted" (backends.codegen.mode_of), without importing code generation
    when it never was: a compiled bundle is loaded only through it."""
    codegen = sys.modules.get("casmech.backends.codegen")
    return codegen.mode_of(functions) if codegen is not None else "interpreted"


def _keep_messages(result: Result, messages: list[str], count: int) -> None:
    if count:
        result.metadata.update(solver_messages=messages, solver_message_count=count)


def analysis_settings(functions: SystemFunctions, analysis: str | None = None,
                      t_end: float | None = None, output_step: float | None = None,
                      rtol: float | None = None, atol: float | None = None,
                      formulation: str | None = None, stabilization: str | None = None,
                      method: str | None = None) -> Analysis:
    """The settings `analyze` runs with (its arguments over the model's `analysis:` block),
    checked: a UsageError for an option that does not exist and for values outside
    schema.limits (E409: rtol, atol, t_end, an output grid too large)."""
    settings = functions.ir.analysis
    given = {"type": analysis, "t_end": t_end, "output_step": output_step, "rtol": rtol,
             "atol": atol}
    settings = replace(settings, **{k: v for k, v in given.items() if v is not None})
    asked = {"formulation": formulation, "stabilization": stabilization, "method": method}
    for name, value in asked.items():
        if value is None:
            continue
        if value not in DYNAMICS_OPTIONS[name]:
            raise UsageError(f"{name} '{value}' is not one of "
                             f"{', '.join(DYNAMICS_OPTIONS[name])}")
        settings = replace(settings, options={**settings.options, name: value})
    if settings.options.get("formulation", "auto") == "auto" and (
            stabilization is not None or settings.options.get("stabilization", "ggl") != "ggl"):
        # a DAE stabilization asked for (by the caller, or the file's other than the default)
        # means the r-p DAE: decided here only (runtime.auto_formulation never sees it)
        settings = replace(settings, options={**settings.options, "formulation": "rp"})
    if settings.type not in ANALYSES:
        raise UsageError(f"analysis type '{settings.type}' is not available yet; available: "
                         f"{', '.join(ANALYSES)}")
    numbers = {name: float(getattr(settings, name))
               for name in ("t_end", "output_step", "rtol", "atol")}
    problems = limits.analysis_problems(numbers, len(column_names(functions)), step_within=False)
    if problems:  # the model's own settings were checked when it was loaded: these were given
        raise UsageError("\n".join(f"error[E409] {name} = {numbers[name]:g}: {problem}"
                                    for name, problem in problems.items()))
    return settings


def check(functions: SystemFunctions) -> tuple[Structure, bool]:
    """Structure (DOF, rank, redundant rows) at the assembled configuration, or at the file's
    pose when assembly fails; the flag says whether assembly succeeded."""
    try:
        q = assembly.assemble_positions(functions)
        return structure(functions, 0.0, q), True
    except AnalysisError:
        return structure(functions, 0.0, assembly.initial_guess(functions)), False
