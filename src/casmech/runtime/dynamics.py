"""Forward dynamics in the r-p or r-omega form, integrated by SUNDIALS IDAS through CasADi.

By default IDAS integrates the stabilized index-2 DAE of formulations.dae (stabilization "ggl",
Gear-Gupta-Leimkuhler): x = [q, v], z = [v_dot, lam, mu] (v = q_dot in r-p, [r_dot; omega_bar]
in r-omega), which holds Phi = 0 and P v = nu themselves at every step, with the algebraic
unknowns out of the error test, and needs no projections (measured against the index-1 DAE
below: docs/decisions/ggl-stabilization.md). Its first step is sized by initial_step (IDAS's
own guess is too short for an index-2 iteration matrix).

Stabilization "projection": the index-1 DAE, z = [v_dot, lam]. The position and velocity
constraints then hold at the integration error; at the first output where either drifts past
drift_tolerance(atol) the state is projected back mass-orthogonally (assembly.project) and
IDAS restarts from there. No Baumgarte constants either way. A chunk of output intervals the
index-2 DAE fails on is done this way (run_dynamics).

With ggl the whole output grid is one IDAS call, unless a progress callback wants rows as they
come or the DAE failed (then chunks of `chunk` intervals, core.options.DynamicsSolver, over
runtime.driver); the output rows of a chunk (accelerations and multipliers solved at each
row's state, not read from IDAS's algebraic states: docs/decisions/row-multipliers.md; r-p
rates, true or least-norm multipliers, the index-1 DAE's drift check) are each one mapped
casadi.Function call, never Python per row.

Rows that depend on the others at t0 (redundant joints) are masked out of both DAEs. Every
start hands IDAS the exact derivative and algebraic state (init_xdot, z0), solved here from
the same equations, so IDACalcIC is never needed. Those are options of the integrator, so
integrators are kept per start (runtime.dae_integrators), and so are the mask and the
consistent state (_Model), in the run's workspace (runtime.workspace): a run repeated from the
same state creates and solves neither.

Where the constraint Jacobian loses rank along the motion (the IFToMM A02 N-four-bar passing
its flat poses) both DAEs are singular and IDAS fails; the run then starts over from t0 on the
augmented-Lagrangian ODE (formulations.augmented), which stays well-posed there, integrated by
runtime.projected_rk4: Runge-Kutta steps each projected back onto the constraints, their number
per output interval set by step doubling (metadata augmented_from = t0, dae_failed_at = the
start of the chunk that failed, rk4_steps, rk4_rejected, rk4_stalled_at). A failure of that
one is reported with the output interval, the time and the joints.

Measurements behind these choices (the fallback's history, the rejected alternatives):
docs/decisions/singular-fallback.md and docs/decisions/ggl-stabilization.md.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.core.options import DynamicsOptions, DynamicsSolver
from casmech.equations.checks import dependent_joints
from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError, FailureContext, Interrupted, solver_reason
from casmech.formulations import dae
from casmech.formulations.builtin import masked_rows, row_scales, velocities
from casmech.formulations.dae_options import (
    algebraic_tolerances,
    initial_step,
)
from casmech.formulations.table import BODY_FORMS, BodyForm
from casmech.numerics import kkt
from casmech.runtime import (
    assembly,
    cancel,
    contact_steps,
    dae_integrators,
    dae_rows,
    events,
    nonfinite,
    projected_rk4,
    solver_messages,
)
from casmech.runtime.dae_rows import Rows, mapped
from casmech.runtime.driver import Block, Chunks, completed, drive
from casmech.runtime.kinematics import output_times
from casmech.runtime.results import Result
from casmech.runtime.workspace import Workspace, of

DEFAULT, STABILIZATION = DynamicsSolver(), DynamicsOptions().stabilization  # core.options


def drift_tolerance(atol: float, settings: DynamicsSolver = DEFAULT) -> float:
    """Constraint drift allowed before a projection: settings.drift_tolerance, or 100 atol
    when the integration itself is looser. Every projection restarts IDAS (a new integrator),
    so a tighter multiple of atol projects far more often for no accuracy
    (docs/decisions/ggl-stabilization.md)."""
    return max(settings.drift_tolerance, 100 * atol)


def penalty(functions: SystemFunctions, form: BodyForm, q,
            settings: DynamicsSolver = DEFAULT) -> float:
    """The augmented-Lagrangian penalty scaled to the model: fallback.penalty max(diag M)."""
    return settings.fallback.penalty * np.max(np.diag(functions.matrix(form.mass, q)),
                                              initial=1.0)


def _frozen(*arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    """The arrays, read-only (kept ones are shared by later runs)."""
    for a in arrays:
        a.setflags(write=False)
    return arrays


class _Model:
    """The numeric side of one formulation: row scales, consistent (v_dot, lam), q_dot. The
    mask and the consistent state at a start are kept in the workspace, so a run from the
    same state computes neither again."""

    def __init__(self, functions: SystemFunctions, name: str, settings: DynamicsSolver = DEFAULT,
                 workspace: Workspace | None = None):
        self.functions, self.name, self.form = functions, name, BODY_FORMS[name]
        self.settings, self.workspace = settings, of(functions, workspace)
        self.n_q, self.n_v, self.m = dae.sizes(functions.functions, name)

    def start(self, t, q, v, mask) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(s, s_phi, v_dot, lam / s) at (t, q, v): scales, then consistent."""
        key = ("start", self.name, float(t), *(np.asarray(a, float).tobytes()
                                                for a in (q, v, mask)))

        def build():
            s, s_phi = self.scales(t, q)
            return _frozen(s, s_phi, *self.consistent(t, q, v, mask, s))

        return self.workspace.kept("dae_starts", key, build)

    def scales(self, t, q) -> tuple[np.ndarray, np.ndarray]:
        """(s, s_phi): the DAEs' row scales (formulations.builtin.row_scales)."""
        return row_scales(self.functions, self.name, t, q)

    def mask(self, t, q) -> np.ndarray:
        """1 for every row dropped from the DAE, else 0 (formulations.builtin.masked_rows)."""
        limits = self.settings.assembly.linear_algebra

        def build():
            return _frozen(masked_rows(self.functions, self.name, t, q, limits))[0]

        key = ("mask", self.name, float(t), np.asarray(q, float).tobytes(), limits)
        return self.workspace.kept("dae_starts", key, build)

    def consistent(self, t, q, v, mask, s) -> tuple[np.ndarray, np.ndarray]:
        """(v_dot, lam / s) solving the DAE's algebraic equations at (t, q, v) with row
        scales s (the DAE's lam: the true multipliers are s * lam): numerics.kkt.saddle on
        [M P_s^T; P_s -diag(mask)] (the least-squares solution where that is singular: a
        singular configuration at the start)."""
        f, form = self.functions, self.form
        mass, jac = f[form.mass](q), ca.mtimes(ca.diag(ca.DM(s)), f[form.jacobian](t, q))
        gamma, forces = f.vector(form.gamma, t, q, v) * s, f[form.forces](t, q, v)
        saddle = self.workspace.kept("dae_saddle", self.name,
                                     lambda: kkt.saddle(mass.sparsity(), jac.sparsity()))
        return assembly.saddle_solution(saddle, mass, jac, forces, gamma, mask)

    def accelerations(self, t, q, v, mask) -> tuple[np.ndarray, np.ndarray]:
        """(v_dot, true multipliers) at (t, q, v)."""
        s, _, v_dot, lam = self.start(t, q, v, mask)
        return v_dot, s * lam

    def solved(self, times: np.ndarray, states: np.ndarray, mask, s
               ) -> tuple[np.ndarray, np.ndarray]:
        """(states, true multipliers) of the integrator's states at `times`: rows [q, v, v_dot]
        with v_dot and the multipliers solved at each column's (t, q, v) with row scales s,
        one mapped call (dae_rows.solve); a column whose saddle matrix is singular by
        `consistent`'s least squares."""
        q, v = states[:self.n_q], states[self.n_q:self.n_q + self.n_v]
        solve = self.workspace.kept("dae_rows", ("solve", self.name),
                                    lambda: dae_rows.solve(self.functions, self.name))
        try:
            with solver_messages.without_input_dumps():
                v_dot, lam = mapped(solve, times[None, :], q, v, mask[:, None], s[:, None],
                                    workspace=self.workspace)
        except RuntimeError as error:  # the LU met a zero pivot
            cancel.check(error)
            v_dot, lam = np.full((self.n_v, len(times)), np.nan), np.full((self.m, len(times)),
                                                                         np.nan)
        for j in np.flatnonzero(~(np.isfinite(v_dot).all(0) & np.isfinite(lam).all(0))):
            v_dot[:, j], lam[:, j] = self.consistent(times[j], q[:, j], v[:, j], mask, s)
        return np.vstack([q, v, v_dot]), s[:, None] * lam

    def q_dot(self, q, v) -> np.ndarray:
        if self.form.q_dot is None:
            return np.asarray(v, float)
        return self.functions.vector(self.form.q_dot, q, v)


class _Stepper:
    """Integrates from a state over a chunk of the output grid: by the DAE until it first
    fails, by the augmented-Lagrangian ODE from there on (a model that has met a singular
    configuration will meet it again; the DAE only fails there after thousands of steps), or
    from t0 with fallback.always. With ggl, the first chunk is the whole grid; after a
    failure, chunks of settings.chunk intervals, and a chunk the index-2 DAE fails on is done
    by the index-1 DAE, the next one by the index-2 one again (the two DAEs have the same
    solution). The index-1 DAE (projection) and a run with a progress callback start at
    settings.chunk intervals."""

    def __init__(self, model: _Model, rtol: float, atol: float,
                 stabilization: str = STABILIZATION):
        self.model, self.stabilization, self.settings = model, stabilization, model.settings
        self.chunks = Chunks(self.settings.chunk, grow=True)  # kept over a restart on the ODE
        self.ggl_failures: list[float] = []  # chunk starts the index-2 DAE failed at
        self.options = {"reltol": rtol, "abstol": atol, "disable_internal_warnings": True,
                        **nonfinite.SOLVER_OPTIONS}
        self.fallback = None  # projected_rk4.ProjectedRK4, built when first needed
        self.on_ode, self.switched_at, self.dae_reason = self.settings.fallback.always, None, ""
        self.idas_calls, self.idas_steps = 0, 0
        self.t_start = None  # the run's t0: integrators from there are kept (_dae)

    def start(self, t0: float, intervals: int, progress: bool) -> Chunks:
        """The chunks of a run from t0 over `intervals` output intervals: the first all of
        them for the index-2 DAE unless it failed before or a progress callback wants rows as
        they come."""
        self.t_start = t0
        whole = (self.stabilization == "ggl" and not self.on_ode and not progress
                 and self.chunks.limit is None)
        self.chunks.size = max(intervals, 1) if whole else self.settings.chunk
        return self.chunks

    def integrate(self, t0: float, times: np.ndarray, q, v, mask):
        """(states, lam, kind) at `times` or a first part of them: states rows [q, v, v_dot],
        lam the true multipliers, kind "ggl", "projection" or "ode" (which made them).

        By the DAE until it first fails (then _Restart: the run starts over on the
        augmented-Lagrangian ODE), else by that ODE. Equations of motion that are not finite
        fail at once (the RuntimeError, which the driver narrows to one output interval:
        runtime.nonfinite), on no other DAE or integrator."""
        if self.on_ode:
            return (*self._ode(t0, times, q, v), "ode")
        chunk = self.settings.chunk
        if self.stabilization == "ggl" and len(self.ggl_failures) < self.settings.ggl_failures:
            try:
                return (*self._dae(t0, times, q, v, mask, "ggl"), "ggl")
            except RuntimeError as error:
                cancel.check(error)  # a signal is not a solver failure
                if nonfinite.rates_failed(error):
                    raise
                if len(times) > chunk:  # the whole grid: again in chunks, as after a failure
                    self.chunks.cap(chunk)
                    return self.integrate(t0, times[:chunk], q, v, mask)
                self.ggl_failures.append(float(t0))
                self.chunks.limit = chunk
        try:
            return (*self._dae(t0, times, q, v, mask, "projection"), "projection")
        except RuntimeError as error:  # IDAS failed (its construction is not guarded)
            cancel.check(error)
            if nonfinite.rates_failed(error):
                raise
            raise _Restart(float(t0), solver_reason(error)) from None

    def probe(self, kind: str, t0: float, t: float, t1: float, q, v, mask):
        """(states, lam) at the one time t in (t0, t1) from (t0, q, v), by what made the block
        (`kind` as integrate returns it): an event's trial point (runtime.events). The DAE
        integrates to t1 with the first step of the interval (t0, t1) and gives t from its
        interpolant: a trial point just after t0 would otherwise start the index-2 DAE with
        a step too short for its iteration matrix (the four-bar failed at 1e-9 s), and every
        trial of one interval reads the same steps."""
        if kind == "ode":
            return self._ode(t0, np.array([t]), q, v)
        states, lam = self._dae(t0, np.array([t, t1]), q, v, mask, kind, t1 - t0)
        return states[:, :1], lam[:, :1]

    def _dae(self, t0, times, q, v, mask, kind: str, first: float | None = None):
        """IDAS on the DAE from the exact consistent state, handed over with its derivative
        (init_xdot, z0) instead of asking IDACalcIC, whose line search often fails (IFToMM
        A01's 1e-9 inertia; docs/decisions/rp-integrators-kept.md). `first`: the
        output interval the first step is sized by (default the first of `times`). Only an
        integrator from the run's start is kept (a repeated run starts there; a restart
        within the run from there on is not repeated but by the same run again)."""
        model, settings = self.model, self.settings
        s, s_phi, v_dot, lam = model.start(t0, q, v, mask)
        x_dot = np.concatenate([model.q_dot(q, v), v_dot])
        n_z = model.n_v + dae.multipliers(model.functions.functions, model.name, kind)
        rtol, atol = self.options["reltol"], self.options["abstol"]
        floor = settings.algebraic_tolerance if kind == "ggl" else atol
        options = {"suppress_algebraic": True, "calc_ic": False, "init_xdot": list(x_dot),
                   "abstolv": list(np.concatenate([
                       np.full(len(q) + len(v), atol),
                       algebraic_tolerances(rtol, floor, v_dot, lam, n_z,
                                            settings.mu_tolerance)]))}
        p = [[t0], mask, s]
        if kind == "ggl":
            n = 3 * model.functions.n_bodies  # the translations lead q and v in both forms
            if settings.initial_step is None:
                options["step0"] = initial_step(q[:n], v_dot[:n], rtol, atol,
                                                first or times[0] - t0)
            p.append(s_phi)
        integrator = dae_integrators.integrator(model.functions, model.name, kind, times - t0,
                                                self.options | options,
                                                keep=first is None and t0 == self.t_start,
                                                workspace=model.workspace)
        z0 = np.zeros(n_z)  # GGL's mu is 0 along the exact motion
        z0[:len(v_dot) + len(lam)] = np.concatenate([v_dot, lam])
        self.idas_calls += 1
        try:
            data = model.functions.data  # a compiled parametric DAE's model data
            out = integrator(x0=np.concatenate([q, v]), z0=z0,
                             p=np.concatenate(p if data is None else [*p, data]))
        except Interrupted as interrupted:  # the grid points it had done are kept
            done = getattr(interrupted, "outputs", None)
            count = 0 if done is None else completed(done["xf"], done["zf"])
            if count:
                x = self._dae_states({k: v[:, :count] for k, v in done.items()})
                interrupted.done = (*model.solved(times[:count], x, mask, s), kind)
            raise
        finally:
            self.idas_steps += int(integrator.stats().get("nsteps", 0))
        return model.solved(times, self._dae_states(out), mask, s)

    @staticmethod
    def _dae_states(out) -> np.ndarray:
        """The integrator's x = [q, v] at its output times (its algebraic states are checked
        only: the rows solve v_dot and the multipliers at each state, _Model.solved)."""
        x, z = np.array(out["xf"]), np.array(out["zf"])
        if not nonfinite.all_finite(x, z):
            raise RuntimeError("the state became NaN or infinite")
        return x

    def _ode(self, t0, times, q, v):
        """The augmented-Lagrangian ODE by projected Runge-Kutta steps over the chunk. On a
        failure, the intervals done so far (the caller records them and comes back for the
        failed one); on the chunk's first interval, the error naming it."""
        model = self.model
        if self.fallback is None:
            functions = model.functions.functions  # evaluated only: compiled ones serve too
            self.fallback = projected_rk4.ProjectedRK4(
                functions, model.name, self.options["reltol"], self.options["abstol"],
                self.settings.fallback)
        a = penalty(model.functions, model.form, q, self.settings)
        x, columns, start = np.concatenate([q, v]), [], t0
        for t in times:
            try:
                x = self.fallback.advance(start, t, x, a)
            except projected_rk4.StatesNotFinite:
                if not columns:
                    raise nonfinite.RatesNotFinite(start, t) from None
                break
            except projected_rk4.StepFailure as error:
                if not columns:
                    raise self.failure(start, t, x[:model.n_q], str(error)) from None
                break
            except Interrupted as interrupted:  # the intervals done are kept
                if columns:
                    interrupted.done = (*self._ode_rows(times, columns, a), "ode")
                raise
            columns.append(x)
            start = t
        return self._ode_rows(times, columns, a)

    def _ode_rows(self, times, columns: list, a: float):
        """(states, lam) of the ODE's states at the first len(columns) times."""
        model = self.model
        states = np.array(columns).T
        done = times[None, :states.shape[1]]
        q_block, v_block = states[:model.n_q], states[model.n_q:]
        v_dot, lam = mapped(self.fallback.accelerations, done, q_block, v_block,
                            np.full((1, done.shape[1]), a))
        return np.vstack([states, v_dot]), lam

    def failure(self, t0, t1, q, why) -> AnalysisError:
        functions = self.model.functions
        dae = (f", after the DAE failed at t = {self.switched_at:.6g} ({self.dae_reason})"
               if self.dae_reason else "")
        cause = (f"the augmented-Lagrangian Runge-Kutta steps failed between t = {t0:.6g} and "
                 f"{t1:.6g} ({why}){dae}; the joints whose "
                 "rows are closest to dependent (a singular configuration?):")
        return AnalysisError(FailureContext(t0, cause, dependent_joints(
            functions, functions.matrix("phi_q", t0, q),
            limits=self.settings.assembly.linear_algebra), "weight in the dependency"))


class _Restart(Exception):
    """The exact DAE failed in the chunk starting at `t`; `reason`: what IDAS said."""

    def __init__(self, t: float, reason: str = ""):
        super().__init__(t)
        self.t, self.reason = t, reason


def run_dynamics(functions: SystemFunctions, t_end: float, step: float, rtol: float,
                 atol: float, t0: float = 0.0, formulation: str = "rp",
                 progress=None, stabilization: str = STABILIZATION, extra_events=(),
                 settings: DynamicsSolver = DEFAULT,
                 workspace: Workspace | None = None) -> Result:
    """By the stabilized index-2 DAE (ggl) or the index-1 DAE with projections; a chunk of
    output intervals the index-2 DAE fails on is done by the index-1 one (metadata
    ggl_failed_at, ggl_failures). If the index-1 DAE fails too (IFToMM A02 at its flat poses),
    the whole run again from t0 on the augmented-Lagrangian ODE, not from the failed chunk:
    a DAE may pass a singular pose before it fails, and starting over keeps every row off a
    DAE that has met one, at the cost of the DAE's time to its failure
    (docs/decisions/singular-fallback.md).

    The model's `events:` and `extra_events` (runtime.events.Event, declared by code) are
    located and recorded in Result.events; without any, no event work is done."""
    model = _Model(functions, formulation, settings, workspace)
    stepper = _Stepper(model, rtol, atol, stabilization)
    stepper.options |= contact_steps.options(functions.ir, step, t_end - t0, settings)
    try:
        return _run(model, stepper, t0, t_end, step, atol, progress, extra_events)
    except _Restart as restart:
        stepper.on_ode, stepper.switched_at, stepper.dae_reason = True, restart.t, restart.reason
        return _run(model, stepper, t0, t_end, step, atol, progress, extra_events)


def _run(model: _Model, stepper: _Stepper, t0: float, t_end: float, step: float, atol: float,
         progress, extra_events=()) -> Result:
    functions, settings = model.functions, model.settings
    result = Result("dynamics", on_row=progress)
    watch = events.watch(functions, result, extra_events, stepper.options["reltol"],
                         settings.event_iterations, model.workspace)
    q, q_dot = assembly.initial_state(functions, t0, settings.assembly, model.workspace)
    v = velocities(functions, model.name, q, q_dot)
    mask = model.mask(t0, q)
    rows = Rows(functions, model.name, (model.n_q, model.n_v, model.m), mask,
                drift_tolerance(atol, settings), step, model.workspace)
    times = output_times(t0, t_end, step)
    chunks = stepper.start(t0, len(times) - 1,
                           progress is not None or events.has_stop(watch))
    counts = {"projections": 0}

    def block(t: float, chunk: np.ndarray, state) -> Block:
        """One solver call from (t, state) over `chunk`: the rows up to the first drifted
        one, projected there (index-1 DAE), or all of them; those computed before a signal
        stopped it, attached to the Interrupted (runtime.driver)."""
        q, v = state
        try:
            states, lams, kind = stepper.integrate(t, chunk, q, v, mask)
        except Interrupted as interrupted:
            if getattr(interrupted, "done", None) is not None:
                interrupted.block = made(t, chunk, (q, v), *interrupted.done)
            raise
        return made(t, chunk, (q, v), states, lams, kind)

    def made(t: float, chunk: np.ndarray, start, states, lams, kind: str) -> Block:
        """The Block of the states and multipliers at the leading times of `chunk`."""
        q, v = start
        used = states.shape[1]
        drifted = rows.first_drifted(chunk[:used], states) if kind == "projection" else None
        if drifted is not None:  # project there, record up to it, restart IDAS from it
            used, t_drift = drifted + 1, chunk[drifted]
            q_d, v_d, _ = rows.split(states[:, drifted])
            q_d, v_d = assembly.project(functions, model.form, t_drift, q_d, v_d,
                                        penalty(functions, model.form, q_d, settings),
                                        accept=0.1 * rows.tolerance,
                                        settings=settings.assembly,
                                        fallback=settings.fallback, workspace=model.workspace)
            v_dot, lam = model.accelerations(t_drift, q_d, v_d, mask)
            states[:, drifted], lams[:, drifted] = np.concatenate([q_d, v_d, v_dot]), lam
            counts["projections"] += 1
        done, states, lams = chunk[:used], states[:, :used], lams[:, :used]

        def state_at(j: int):
            return rows.split(states[:, j])[:2]

        def probe(t_start: float, start, t_trial: float, t_stop: float):
            found, lam = stepper.probe(kind, t_start, t_trial, t_stop, *start, mask)
            return rows.rows(np.array([t_trial]), found, lam), rows.split(found[:, 0])[:2]

        return Block(done, rows.rows(done, states, lams), state_at(used - 1), (q, v),
                     state_at, probe, restarted=drifted is not None)

    try:
        v_dot, lam = model.accelerations(times[0], q, v, mask)
        first = rows.rows(times[:1], np.concatenate([q, v, v_dot])[:, None], lam[:, None])
        result.extend(times[:1], *first)
        if watch is not None:
            watch.start(times[0], first)
        drive(result, times, (q, v), block, chunks, watch, halves=True,
              fail=nonfinite.interval_failure)
    except AnalysisError as error:
        error.partial = result
        raise
    result.metadata.update(rtol=stepper.options["reltol"], atol=atol,
                           formulation=model.name, projections=counts["projections"],
                           integrator="projected_rk4" if stepper.on_ode else "idas",
                           stabilization=stepper.stabilization,
                           ggl_failed_at=stepper.ggl_failures[0] if stepper.ggl_failures else None,
                           ggl_failures=len(stepper.ggl_failures),
                           augmented_from=t0 if stepper.on_ode else None,
                           rk4_steps=stepper.fallback.steps if stepper.on_ode else None,
                           rk4_rejected=stepper.fallback.rejected if stepper.on_ode else None,
                           rk4_stalled_at=stepper.fallback.stalled if stepper.on_ode else None,
                           dae_failed_at=stepper.switched_at, dropped_rows=int(mask.sum()),
                           idas_calls=stepper.idas_calls, idas_steps=stepper.idas_steps)
    return result
