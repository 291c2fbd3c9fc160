"""Running an analysis of a system: the analyses by type, the settings a run uses (the model's
`analysis:` block with the caller's overrides and options, checked), and the structure check.

A run gets its typed options (core.options, one dataclass per analysis type), a workspace
(runtime.workspace: what earlier runs on the same bundle built; by default the bundle's own)
and a cancellation token (runtime.cancel: by default the one a `trap()` of runtime.interrupts
installed, else a new one that Ctrl-C cancels during the run).

casmech.api re-exports `analyze`, `analysis_settings` and `check` as the public API.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import fields, replace

from casmech.core import option_values
from casmech.core.options import FORMULATIONS, METHODS, OPTIONS, STABILIZATIONS
from casmech.equations.checks import Structure, structure
from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError, Diagnostic, Interrupted, ModelError, UsageError
from casmech.formulations.registry import FORMULATIONS as REGISTERED
from casmech.runtime import (
    assembly,
    auto_formulation,
    driven_friction,
    formulation_run,
    friction,
    interrupts,
    solver_messages,
)
from casmech.runtime.cancel import CancelToken, current
from casmech.runtime.events import Event
from casmech.runtime.joint_dynamics import tree_of
from casmech.runtime.kinematics import (
    output_count,
    output_times,
    run_assembly,
    run_prescribed_motion,
)
from casmech.runtime.nonfinite import NonFinite
from casmech.runtime.results import Result, column_names
from casmech.runtime.workspace import Workspace, of
from casmech.schema import limits
from casmech.schema.resolved import Analysis

# dynamics options a caller may override by name (casmech run's flags) -> their choices
# (formulations: the registered ones and auto, kept current by formulations.registry)
DYNAMICS_OPTIONS = {"formulation": FORMULATIONS, "stabilization": STABILIZATIONS,
                    "method": METHODS}


def _dynamics(f: SystemFunctions, s: Analysis, progress, workspace: Workspace,
              extra_events=(), plan: _Plan | None = None) -> Result:
    """A model with joint friction or exact contact friction: segments in its modes
    (runtime.friction); else one run. The load parts of driven coordinates' frictions are
    added to the rows, and to a failed run's (runtime.driven_friction). Which of these a
    model has is found once per workspace; a `plan`'s one run is kept in it."""
    switched, loaded = workspace.one("frictions", lambda: (
        friction.switched(f.ir), bool(driven_friction.elements(f.ir))))
    if not (switched or loaded):
        one = _Segment(f, s, workspace, extra_events)
        if plan is not None:
            plan.dynamics = one
        return one.run(f, progress)
    try:
        if switched:
            def segment(functions, span, events):
                return _run_dynamics(functions, s, None, None, events, span)

            result = friction.run(f, s, progress, segment, extra_events)
        else:
            result = _run_dynamics(f, s, progress, workspace, extra_events)
    except AnalysisError as error:
        error.partial = driven_friction.amended(f, error.partial)
        raise
    return driven_friction.amended(f, result)


def _run_dynamics(f: SystemFunctions, s: Analysis, progress, workspace: Workspace | None,
                  extra_events=(), span=None) -> Result:
    """One segment's run (_Segment)."""
    return _Segment(f, s, workspace, extra_events, span).run(f, progress)


class _Segment:
    """A dynamics run of one segment: by the formulation asked for, taken from the registry
    (formulations.registry; its run: runtime.formulation_run); auto: runtime.auto_formulation,
    which also examines a mechanism with loops for singular poses. `span`: (t0, t_end, output
    step), by default the analysis's from 0. Its run of joint coordinates is prepared by its
    first run (formulation_run.prepared_joint) and kept for the next (a _Plan's), while the
    built-in formulation is registered as "joint"; the bundle is not held."""

    def __init__(self, f: SystemFunctions, s: Analysis, workspace: Workspace | None,
                 extra_events=(), span=None):
        t0, t_end, step = span or (0.0, s.t_end, s.output_step)
        self.asked = formulation_run.Run(t0, t_end, step, s.rtol, s.atol, s.options, None,
                                         tuple(extra_events), workspace)
        self.tree, self.rows = tree_of(f, workspace), output_count(t0, t_end, step)
        options = s.options
        self.first = auto_formulation.first_of(f, self.tree, options.formulation, self.rows,
                                               options.solver, workspace, options.method)
        self.joint = self.formulation = None

    def run(self, f: SystemFunctions, progress) -> Result:
        asked = self.asked
        options = asked.options

        def other(name: str) -> Result:
            return formulation_run.run(f, name, replace(asked, progress=progress))

        def joint() -> Result:
            prepared, registered = self.joint, REGISTERED.get("joint")
            if prepared is None or self.formulation is not registered:
                prepared = formulation_run.prepared_joint(f, asked)
                if prepared is None:
                    return other("joint")
                self.joint, self.formulation = prepared, registered
            return prepared.run(f, progress, asked.extra_events)

        return auto_formulation.run(f, self.tree, options.formulation, self.rows, joint,
                                    other, options.solver, asked.workspace, options.method,
                                    self.first)


def _runtime(name: str):
    """A runtime module imported on use (statics and modal need scipy.linalg)."""
    return importlib.import_module(f"casmech.runtime.{name}")


def _prescribed(f: SystemFunctions, s: Analysis, progress, workspace: Workspace) -> Result:
    return run_prescribed_motion(f, s.t_end, s.output_step, s.type, progress=progress,
                                 settings=s.options.solver, workspace=workspace)


def _modal(f: SystemFunctions, s: Analysis, progress, workspace: Workspace) -> Result:
    def dynamics(functions, settings, on_row):
        return _dynamics(functions, settings, on_row, workspace)

    return _runtime("modal").run_modal(f, s, progress=progress, dynamics=dynamics,
                                       workspace=workspace)


# analysis type -> run(functions, settings, progress, workspace); settings is the model's
# `analysis:` block with the caller's overrides applied, its options typed for the type.
ANALYSES: dict[str, Callable[[SystemFunctions, Analysis, Callable | None, Workspace], Result]] = {
    "kinematics": _prescribed,
    "inverse_dynamics": _prescribed,
    "assembly": lambda f, s, p, w: run_assembly(f, progress=p,
                                                settings=s.options.solver.assembly, workspace=w),
    "dynamics": _dynamics,
    "statics": lambda f, s, p, w: _runtime("statics").run_statics(
        f, progress=p, settings=s.options.solver, workspace=w),
    "modal": _modal,
}


def analyze(functions: SystemFunctions, analysis: str | None = None, t_end: float | None = None,
            output_step: float | None = None, rtol: float | None = None,
            atol: float | None = None, formulation: str | None = None,
            progress: Callable[[float], None] | None = None,
            stabilization: str | None = None, method: str | None = None,
            events: Sequence[Event] = (), options=None, workspace: Workspace | None = None,
            token: CancelToken | None = None, controller: Callable | None = None,
            controls: Sequence[str] | str | None = None) -> Result:
    """Run an analysis; the model's `analysis:` block gives what is not passed (for dynamics:
    formulation "auto", "joint", "rp", "romega" or another registered one
    (formulations.registry), stabilization "ggl" or "projection" of the
    DAEs, method "auto", "adams" or "bdf" of joint coordinates on a tree; docs/formulations.md).
    `options`: the analysis type's options (a casmech.core.options dataclass, replacing the
    file's, or a mapping of keys such as {"max_step": 1e-3, "solver.assembly.tolerance":
    1e-10} over the file's; docs/analyses.md#options). `progress`, when given, is called with
    the time of every output row as it is computed. `workspace`: where the run keeps what it
    builds for later runs (runtime.workspace; default: the bundle's own). `token`: a
    runtime.cancel.CancelToken whose cancel() stops the run with errors.Interrupted carrying
    the rows computed so far (default: Ctrl-C does). The Result keeps `functions`:
    `result.to_dataframe()` is its results table as a DataFrame. `events`: runtime.events.Event
    declared by code, watched by dynamics besides the model's `events:` (Result.events,
    Result.events_dataframe()). `controller(t, state) -> efforts`: the torques and forces of
    the effort motors `controls` names (default: all of them) during a dynamics run
    (runtime.controller; docs/api.md#controllers)."""
    if controller is not None or controls is not None:
        return _controlled(functions, controller, controls, dict(
            analysis=analysis, t_end=t_end, output_step=output_step, rtol=rtol, atol=atol,
            formulation=formulation, progress=progress, stabilization=stabilization,
            method=method, events=events, options=options, workspace=workspace, token=token))
    given = (analysis, t_end, output_step, rtol, atol, formulation, stabilization, method,
             options)
    workspace = of(functions, workspace)
    plan = None if events else _plan(functions, given, workspace)
    settings = analysis_settings(functions, *given) if plan is None else plan.settings
    if events and settings.type != "dynamics":
        raise UsageError(f"events are watched by dynamics, not by {settings.type}")
    run = ANALYSES[settings.type] if not events else (
        lambda f, s, p, w: _dynamics(f, s, p, w, tuple(events)))
    if plan is not None and run is _dynamics:
        run = plan.dynamics_run
    messages: list[str] = []  # the solvers' own stderr lines (runtime.solver_messages)
    try:
        with workspace.lock, interrupts.guard(token or current() or CancelToken()), \
                solver_messages.collected(messages) as stream:
            result = run(functions, settings, progress, workspace)
    except AnalysisError as error:  # the rows before a failure tabulate like a whole run's
        if error.partial is not None:
            error.partial.functions = functions
            error.partial.status = "interrupted" if isinstance(error, Interrupted) else "failed"
            _keep_messages(error.partial, messages, stream.count)
        if isinstance(error, NonFinite):  # the results column and the elements, by name
            error.explain(functions)
        raise
    _keep_messages(result, messages, stream.count)
    result.metadata.update(analysis=settings.type,
                           mode=mode_of(functions) if plan is None else plan.mode)
    result.functions = functions
    return result


class _Plan:
    """What `analyze` derives from its arguments for one bundle, kept in the run's workspace
    under them (with their types: kind "analysis_plans"), so that the same analysis asked
    again checks nothing and builds nothing again: the checked settings, the bundle's mode
    (compiled or interpreted: the metadata's) and, for dynamics of one segment (no friction
    switched or amended) without events, that run (_Segment, its run of joint coordinates
    prepared). It holds no bundle: the workspace's bundle is the one it serves."""

    def __init__(self, settings: Analysis, mode: str):
        self.settings, self.mode, self.dynamics = settings, mode, None

    def dynamics_run(self, f: SystemFunctions, s: Analysis, progress,
                     workspace: Workspace) -> Result:
        if self.dynamics is not None:
            return self.dynamics.run(f, progress)
        return _dynamics(f, s, progress, workspace, (), self)


def _plan(functions: SystemFunctions, given: tuple, workspace: Workspace) -> _Plan | None:
    """The plan of analyze's arguments `given` (analysis_settings' order) in `workspace`; None
    where they do not hash (options as a mapping: checked every time)."""
    key = _key(given)
    if key is None:
        return None
    return workspace.kept("analysis_plans", key,
                          lambda: _Plan(analysis_settings(functions, *given),
                                        mode_of(functions)))


def _controlled(functions: SystemFunctions, controller, controls, arguments: dict) -> Result:
    """A dynamics run with a Python controller (runtime.controller)."""
    if controller is None:
        raise UsageError("controls names the motors a controller drives: pass controller= too")
    given = ("analysis", "t_end", "output_step", "rtol", "atol", "formulation")
    settings = analysis_settings(functions, *(arguments[name] for name in given))
    if settings.type != "dynamics":
        raise UsageError(f"a controller drives a dynamics run, not {settings.type}")
    if friction.switched(functions.ir):
        raise UsageError("a controller does not run with joint friction or exact contact "
                         "friction (its runs are segments of rebuilt functions)")
    if arguments["workspace"] is not None:
        raise UsageError("a controlled run builds its own functions: give no workspace")
    from casmech.runtime import controller as controllers

    progress, token = arguments.pop("progress"), arguments.pop("token") or current()

    def run(bundle, rows, run_token, t_end):
        return analyze(bundle, progress=rows, token=run_token,
                       **(arguments | ({"t_end": t_end} if t_end is not None else {})))

    return controllers.run(functions, controller, controls, progress, token,
                           output_times(0.0, settings.t_end, settings.output_step), run)


def mode_of(functions: SystemFunctions) -> str:
    """"compiled" or "interpreted" (backends.codegen.mode_of), without importing code generation
    when it never was: a compiled bundle is loaded only through it."""
    codegen = sys.modules.get("casmech.backends.codegen")
    return codegen.mode_of(functions) if codegen is not None else "interpreted"


def _keep_messages(result: Result, messages: list[str], count: int) -> None:
    if count:
        result.metadata.update(solver_messages=messages, solver_message_count=count)


def options_of(kind: str, written) -> object:
    """The options of analysis type `kind` from the option keys a model wrote (those the
    type has; the file's block was checked against its own type)."""
    cls = OPTIONS[kind]
    mine = {key: value for key, value in written if option_values.lookup(cls, key) is not None}
    options, _ = option_values.with_values(cls(), mine)
    return options


def typed_options(kind: str, base, options) -> object:
    """`base` (options of type `kind`) with the caller's `options`: a dataclass of that type
    (replacing them) or a mapping of keys over them (values of their types, or texts as the
    command line gives them); a UsageError naming every problem."""
    cls = OPTIONS[kind]
    if options is None:
        return base
    if isinstance(options, cls):
        return options
    if option_values.is_options(type(options)):
        raise UsageError(f"options of a {kind} analysis are a {cls.__name__} (or a mapping), "
                         f"not a {type(options).__name__}")
    if not isinstance(options, Mapping):
        raise UsageError(f"options must be a {cls.__name__} or a mapping of option keys, not "
                         f"{type(options).__name__}")
    typed, problems = option_values.with_values(base, options, text=True)
    if problems:
        raise UsageError("\n".join(f"{kind} {problem.line()}" for problem in problems))
    return typed


def analysis_settings(functions: SystemFunctions, analysis: str | None = None,
                      t_end: float | None = None, output_step: float | None = None,
                      rtol: float | None = None, atol: float | None = None,
                      formulation: str | None = None, stabilization: str | None = None,
                      method: str | None = None, options=None) -> Analysis:
    """The settings `analyze` runs with (its arguments over the model's `analysis:` block),
    checked: a UsageError for an analysis type or option that does not exist, a value of
    the wrong type or out of range, and for values outside schema.limits (E409: rtol, atol,
    t_end, an output grid too large). A type other than the file's takes the option keys
    the file wrote that it has; formulation, stabilization and method apply to the types
    that have them (dynamics, modal). Checked settings are kept in the bundle's workspace by
    the arguments (and their types) that made them, so a repeated run checks them once."""
    given = (analysis, t_end, output_step, rtol, atol, formulation, stabilization, method,
             options)
    key = _key(given)
    if key is None:  # options as a mapping: checked every time
        return _settings(functions, *given)
    return of(functions, None).kept("analysis_settings", key,
                                    lambda: _settings(functions, *given))


def _key(given: tuple) -> tuple | None:
    """analysis_settings' arguments `given` with their types, as a key; None where they do
    not hash (options as a mapping)."""
    key = (*given, *map(type, given))
    try:
        hash(key)
    except TypeError:
        return None
    return key


def _settings(functions: SystemFunctions, analysis, t_end, output_step, rtol, atol,
              formulation, stabilization, method, options) -> Analysis:
    settings = functions.ir.analysis
    given = {"type": analysis, "t_end": t_end, "output_step": output_step, "rtol": rtol,
             "atol": atol}
    settings = replace(settings, **{k: v for k, v in given.items() if v is not None})
    if settings.type not in ANALYSES:
        raise UsageError(f"analysis type '{settings.type}' is not available yet; available: "
                         f"{', '.join(ANALYSES)}")
    typed = settings.options
    if not isinstance(typed, OPTIONS[settings.type]):
        typed = options_of(settings.type, settings.written)
    typed = typed_options(settings.type, typed, options)
    names = {f.name for f in fields(typed)}
    asked = {"formulation": formulation, "stabilization": stabilization, "method": method}
    for name, value in asked.items():
        if value is None:
            continue
        if value not in DYNAMICS_OPTIONS[name]:
            raise UsageError(f"{name} '{value}' is not one of "
                             f"{', '.join(DYNAMICS_OPTIONS[name])}")
        if name in names:
            typed = replace(typed, **{name: value})
    stabilized = "formulation" in names and typed.formulation == "auto" and (
        stabilization is not None or typed.stabilization != "ggl")
    if stabilized:
        # a DAE stabilization asked for means the r-p DAE: decided here only
        # (runtime.auto_formulation never sees it)
        typed = replace(typed, formulation="rp")
    settings = replace(settings, options=typed)
    if "method" in names:
        _method_runs(functions, typed.formulation, typed.method,
                     (formulation, stabilization, method) == (None, None, None), stabilized)
    numbers = {name: float(getattr(settings, name))
               for name in ("t_end", "output_step", "rtol", "atol")}
    problems = limits.analysis_problems(numbers, len(column_names(functions)), step_within=False)
    written = dict(functions.ir.analysis.sources)
    if problems and all(given[name] is None and name in written for name in problems):
        # the file's own settings (an output grid too large for its results table): located
        raise ModelError([Diagnostic("E409", f"analysis.{name}", problem, written[name],
                                     got=f"{numbers[name]:g}",
                                     hint=limits.HINTS.get(name))
                          for name, problem in problems.items()])
    if problems:
        raise UsageError("\n".join(f"error[E409] {name} = {numbers[name]:g}: {problem}"
                                    for name, problem in problems.items()))
    return settings


def _method_runs(functions: SystemFunctions, formulation: str, method: str,
                 files: bool, stabilized: bool) -> None:
    """E409 when the method does not run under the formulation (runtime.auto_formulation.
    method_problem): located at the file's `method` when the file's settings make it (`files`:
    no formulation, stabilization or method of the caller's), else a UsageError. `stabilized`:
    rp is auto's for a stabilization asked for."""
    found = auto_formulation.method_problem(lambda: tree_of(functions), formulation, method,
                                            functions.body_names)
    if found is None:
        return
    problem, hint = found
    if stabilized:
        problem += " (a DAE stabilization asked for makes formulation auto run rp)"
        hint = "leave the stabilization out (auto, joint coordinates), or remove method"
    source = dict(functions.ir.analysis.sources).get("method")
    if files and source is not None:
        raise ModelError([Diagnostic("E409", "analysis.method", problem, source,
                                     expected="auto | bdf", got=method, hint=hint)])
    raise UsageError(f"error[E409] method = {method}: {problem}\n  hint: {hint}")


def check(functions: SystemFunctions) -> tuple[Structure, bool]:
    """Structure (DOF, rank, redundant rows) at the assembled configuration, or at the file's
    pose when assembly fails; the flag says whether assembly succeeded."""
    try:
        q = assembly.assemble_positions(functions)
        return structure(functions, 0.0, q), True
    except AnalysisError:
        return structure(functions, 0.0, assembly.initial_guess(functions)), False
