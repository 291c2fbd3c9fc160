"""A dynamics run of a registered formulation (formulations.registry.FORMULATIONS), by name.

The built-in classes run through the runtime's drivers for them (RUNS): body coordinates
through runtime.dynamics (its projections, the index-1 chunks after a GGL failure, the
singular-pose fallback), joint coordinates through runtime.joint_dynamics (compiled and
library systems, the method choice, least-norm reactions). Any other formulation runs by
`generic`: its System (formulations.protocol) integrated from its Start by CVODES (an ODE) or
IDAS (a DAE, started from the formulation's consistent z with IDAS's initial-condition
calculation off) over the output grid by runtime.driver, each block's results rows one mapped
call of the System's `rows`.
"""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca
import numpy as np

from casmech.core.options import DynamicsOptions, DynamicsSolver
from casmech.core.records import record
from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError, FailureContext, Interrupted, solver_reason
from casmech.formulations.builtin import BodyCoordinates, JointCoordinates
from casmech.formulations.protocol import Formulation, System
from casmech.formulations.registry import FORMULATIONS
from casmech.runtime import assembly, contact_steps, events
from casmech.runtime.buffers import NamedCall
from casmech.runtime.driver import Block, Chunks, completed, drive
from casmech.runtime.joint_dynamics import prepare
from casmech.runtime.joint_run import JointRun
from casmech.runtime.kinematics import output_times
from casmech.runtime.nonfinite import all_finite
from casmech.runtime.results import Result
from casmech.runtime.workspace import Workspace, of


@record
class Run:
    """What a dynamics run is asked: the output grid from t0 to t_end by step, the
    tolerances, the analysis's options, the progress callback, the events declared by code
    and the workspace."""

    t0: float
    t_end: float
    step: float
    rtol: float
    atol: float
    options: DynamicsOptions
    progress: Callable[[float], None] | None = None
    extra_events: tuple = ()
    workspace: Workspace | None = None


def run(functions: SystemFunctions, name: str, asked: Run) -> Result:
    """The run of the formulation registered as `name`."""
    formulation = FORMULATIONS[name]
    return RUNS.get(type(formulation), generic)(functions, formulation, asked)


def _body(functions: SystemFunctions, formulation: Formulation, asked: Run) -> Result:
    from casmech.runtime.dynamics import run_dynamics

    options = asked.options
    return run_dynamics(functions, asked.t_end, asked.step, asked.rtol, asked.atol,
                        t0=asked.t0, formulation=formulation.name, progress=asked.progress,
                        stabilization=options.stabilization, extra_events=asked.extra_events,
                        settings=options.solver, workspace=asked.workspace)


def _joint(functions: SystemFunctions, formulation: Formulation, asked: Run) -> Result:
    return _prepared(functions, asked).run(functions, asked.progress, asked.extra_events)


def prepared_joint(functions: SystemFunctions, asked: Run) -> JointRun | None:
    """The run of joint coordinates `asked` describes, prepared (runtime.joint_dynamics.prepare;
    its progress and events are its run's), where the formulation registered as "joint" is the
    built-in one; None where another took its name."""
    if RUNS.get(type(FORMULATIONS["joint"])) is not _joint:
        return None
    return _prepared(functions, asked)


def _prepared(functions: SystemFunctions, asked: Run) -> JointRun:
    options = asked.options
    return prepare(functions, asked.t_end, asked.step, asked.rtol, asked.atol, asked.t0,
                   options.method, options.solver, asked.workspace)


def generic(functions: SystemFunctions, formulation: Formulation, asked: Run) -> Result:
    """Any formulation through its protocol (module docstring). The model's `events:` and
    the extra events are located as in the built-in runs."""
    workspace = of(functions, asked.workspace)
    settings, stabilization = asked.options.solver, asked.options.stabilization
    system = workspace.kept("formulation_systems", (formulation, stabilization),
                            lambda: formulation.system(functions, stabilization))
    q0, q_dot0 = assembly.initial_state(functions, asked.t0, settings.assembly, workspace)
    start = formulation.start(functions, system, asked.t0, q0, q_dot0)
    times = output_times(asked.t0, asked.t_end, asked.step)
    integrate = _Integrate(functions, formulation, system, start.p, settings, {
        "reltol": asked.rtol, "abstol": asked.atol, "disable_internal_warnings": True,
        **contact_steps.options(functions.ir, asked.step, asked.t_end - asked.t0, settings)})
    result = Result("dynamics", on_row=asked.progress)
    watch = events.watch(functions, result, asked.extra_events, asked.rtol,
                         settings.event_iterations, workspace)

    def block(t: float, chunk: np.ndarray, state) -> Block:
        """One solver call from (t, state) over `chunk`; the rows computed before a signal
        stopped it, attached to the Interrupted (runtime.driver)."""
        try:
            xs, zs, p = integrate(t, chunk, *state)
        except Interrupted as interrupted:
            if getattr(interrupted, "done", None) is not None:
                interrupted.block = made(t, chunk, state, *interrupted.done)
            raise
        return made(t, chunk, state, xs, zs, p)

    def made(t: float, chunk: np.ndarray, state, xs, zs, p) -> Block:
        chunk = chunk[:xs.shape[1]]

        def probe(t_start: float, at, t_trial: float, t_stop: float):
            # to t_stop, t_trial from the interpolant: an index-2 DAE's first step is sized
            # by the whole interval (as runtime.dynamics' probe)
            found_x, found_z, found_p = integrate(t_start, np.array([t_trial, t_stop]), *at,
                                                  interval=t_stop - t_start)
            return (integrate.rows([t_trial], found_x[:, :1], found_z[:, :1], found_p),
                    (found_x[:, 0], found_z[:, 0]))

        return Block(chunk, integrate.rows(chunk, xs, zs, p), (xs[:, -1], zs[:, -1]), state,
                     lambda j: (xs[:, j], zs[:, j]), probe)

    whole = asked.progress is None and not events.has_stop(watch)
    chunks = Chunks(max(len(times) - 1, 1) if whole else settings.chunk)
    try:
        first = integrate.rows(times[:1], start.x[:, None], start.z[:, None],
                               integrate.parameters(times[0]))
        result.extend(times[:1], *first)
        if watch is not None:
            watch.start(times[0], first)
        drive(result, times, (start.x, start.z), block, chunks, watch, halves=True,
              fail=_failure)
    except AnalysisError as error:
        error.partial = result
        raise
    result.metadata.update(rtol=asked.rtol, atol=asked.atol, formulation=formulation.name,
                           integrator=system.integrator, stabilization=stabilization,
                           steps=integrate.steps)
    return result


class _Integrate:
    """One SUNDIALS call of a System from (t, x, z) over a grid, and the results rows."""

    def __init__(self, functions: SystemFunctions, formulation: Formulation, system: System,
                 p: np.ndarray, settings: DynamicsSolver, options: dict):
        from casmech.formulations import dae

        self.functions, self.formulation, self.settings = functions, formulation, settings
        self.system, self.p, self.options = system, np.asarray(p, float), options
        self.problem = dae.problem(system.residual)
        self.steps = 0

    def parameters(self, t: float) -> np.ndarray:
        """p for a call from t: the start's, with t where the System reads its start time."""
        p = self.p.copy()
        if self.system.time_offset is not None:
            p[self.system.time_offset] = t
        return p

    def __call__(self, t: float, times, x, z, interval: float | None = None):
        """(xs, zs, p) at `times` from (t, x, z); `interval`: the one an index-2 DAE's first
        step is sized by (default the first output interval)."""
        system, p = self.system, self.parameters(t)
        relative = system.time_offset is not None
        origin, grid = (0.0, np.asarray(times) - t) if relative else (t, np.asarray(times))
        options = dict(self.options)
        if system.n_z:  # IDAS from the consistent state, with its exact derivative
            residual = system.residual  # a compiled DAE's has IDAS's u (empty) after p
            u = [np.zeros(residual.size_in(k)) for k in range(4, residual.n_in())]
            x_dot = np.array(residual(origin, x, z, p, *u)[0]).ravel()
            options |= {"calc_ic": False, "init_xdot": list(x_dot), "suppress_algebraic": True}
        options |= self.formulation.integrator_options(
            self.functions, system, origin, np.asarray(x, float), np.asarray(z, float), p,
            options["reltol"], options["abstol"], interval or float(grid[0] - origin),
            self.settings)
        integrator = NamedCall(ca.integrator("formulation", system.integrator, self.problem,
                                             origin, [float(g) for g in grid], options))
        try:
            out = integrator(x0=x, z0=z, p=p)
        except Interrupted as interrupted:  # the grid points done before the signal
            done = getattr(interrupted, "outputs", None)
            outputs = () if done is None else (done["xf"], *([done["zf"]] if system.n_z else []))
            count = completed(*outputs) if outputs else 0
            if count:
                interrupted.done = (done["xf"][:, :count], done["zf"][:, :count]
                                    if system.n_z else np.zeros((0, count)), p)
            raise
        finally:
            self.steps += int(integrator.stats().get("nsteps", 0))
        xs, zs = out["xf"], out["zf"].reshape(system.n_z, len(grid))
        if not all_finite(xs, zs):
            raise RuntimeError("the state became NaN or infinite")
        return xs, zs, p

    def rows(self, times, xs, zs, p):
        """(q, q_dot, q_ddot, lam), one row per time."""
        from casmech.runtime.dae_rows import mapped

        times = np.asarray(times, float)
        relative = times - p[self.system.time_offset] if self.system.time_offset is not None \
            else times
        ps = np.repeat(np.asarray(p, float)[:, None], len(times), axis=1)
        q, q_dot, q_ddot, lam = mapped(self.system.rows, relative[None, :], xs, zs, ps)
        return q.T, q_dot.T, q_ddot.T, lam.T


def _failure(t0: float, t1: float, error: RuntimeError) -> AnalysisError:
    why = solver_reason(error)
    return AnalysisError(FailureContext(
        t0, f"the integrator failed between t = {t0:.6g} and {t1:.6g} "
        f"({why.strip().splitlines()[-1]})", [], ""))


# formulation class -> its run (anything else: generic)
RUNS: dict[type, Callable[[SystemFunctions, Formulation, Run], Result]] = {
    BodyCoordinates: _body,
    JointCoordinates: _joint,
}
