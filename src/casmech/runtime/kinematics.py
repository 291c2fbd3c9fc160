"""Kinematic analysis of a fully driven (0-DOF) mechanism, and inverse dynamics on top of it.

At each output time: positions by Newton from a second-order predictor, velocities from
Phi_q q_dot = nu, accelerations from Phi_q q_ddot = gamma; then the multipliers from the
equations of motion with the prescribed motion, Phi_q^T lam = Q - M q_ddot (inverse dynamics).
With a fully driven mechanism the two analyses differ only in what they are asked for; both
report the joint reactions, since the prescribed motion determines them.

The rows come from one mapped CasADi Function over the output grid (formulations.prescribed); a
row it rejects (Newton not converged in its fixed steps, or Phi_q close to losing rank) is
done by the per-row code (state_at: numpy least squares), which reports a failure with the
joints involved, and the mapped step resumes after it. Blocks hold at most max_block rows
(core.options.KinematicsSolver), and fewer while a block takes longer than BLOCK_SECONDS, so
the run's cancellation token (runtime.cancel), polled between blocks, acts promptly; a block's
length never changes its rows.
"""

from __future__ import annotations

import math
import time

import numpy as np

from casmech.core.options import Assembly, KinematicsSolver
from casmech.equations.checks import structure
from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError, Diagnostic, ModelError
from casmech.formulations import prescribed_friction
from casmech.runtime import assembly, cancel
from casmech.runtime.buffers import BufferedCall
from casmech.runtime.results import Result
from casmech.runtime.workspace import Workspace, of

DEFAULT = KinematicsSolver()
# Rows whose Phi_q has min |R_kk| / max |R_kk| below pivot_ratio go to the per-row code, which
# decides by the singular values whether the configuration is singular (that ratio bounds
# 1/cond from above, so the per-row code sees every row it could reject; numpy's rank cut is
# ~1e-14).
BLOCK_SECONDS = 0.1  # a mapped block longer than this is halved for the next (cancellation)


def output_times(t0: float, t_end: float, step: float) -> np.ndarray:
    """The output grid: t0 + k step up to t_end (within 1e-9 of a step), and t_end itself
    where the last step falls short of it."""
    n, closed = _grid(t0, t_end, step)
    times = t0 + step * np.arange(n + 1)
    return times if closed else np.append(times, t_end)


def output_count(t0: float, t_end: float, step: float) -> int:
    """len(output_times(t0, t_end, step)), without making the grid."""
    n, closed = _grid(t0, t_end, step)
    return n + 1 if closed else n + 2


def _grid(t0: float, t_end: float, step: float) -> tuple[int, bool]:
    """(n, whether t0 + n step, the grid's last multiple of the step, reaches t_end)."""
    n = math.floor((t_end - t0) / step + 1e-9)
    return n, t0 + step * n >= t_end - 1e-9 * step


def require_fully_driven(functions: SystemFunctions, t: float, q: np.ndarray,
                         analysis: str, settings: Assembly = DEFAULT.assembly) -> None:
    report = structure(functions, t, q, settings.linear_algebra)
    if report.dof == 0:
        return
    raise ModelError([Diagnostic(
        "E501", "analysis.type",
        f"{analysis} needs a fully driven mechanism, but this one has {report.dof} "
        "degree(s) of freedom at the assembled configuration",
        functions.ir.analysis.source, expected="0 degrees of freedom", got=f"{report.dof}",
        hint="add drivers (`driver: {angle: ...}` on a revolute joint, `f:` on a basic "
             "constraint) or run a dynamics analysis")])


def state_at(functions: SystemFunctions, t: float, q_guess: np.ndarray, q_dot_guess: np.ndarray,
             settings: Assembly = DEFAULT.assembly):
    q = assembly.newton(functions, t, q_guess, settings=settings)
    q_dot = assembly.solve_velocities(functions, t, q, q_dot_guess, settings)
    q_ddot = assembly.solve_kinematic_accelerations(functions, t, q, q_dot, settings)
    lam = assembly.solve_multipliers(functions, t, q, q_dot, q_ddot)
    return q, q_dot, q_ddot, lam


# Most rows per mapped call (max_block): casadi builds a grid's nested mapaccum in time growing
# faster than its length, so long grids are called in blocks through one kept Function per
# padded length (docs/decisions/output-blocks.md).


def run_prescribed_motion(functions: SystemFunctions, t_end: float, step: float,
                          analysis: str = "kinematics", t0: float = 0.0,
                          progress=None, settings: KinematicsSolver = DEFAULT,
                          workspace: Workspace | None = None) -> Result:
    """Rows by the mapped prescribed step over the grid in blocks of up to max_block rows;
    after a row it rejects (done by state_at) it resumes over max(min_block, twice the rows
    that last passed), doubling while they pass, so the mapped rows computed and discarded
    are at most twice those kept plus min_block per rejected row. metadata per_row_rows: how
    many rows state_at did."""
    result = Result(analysis, on_row=progress)
    result.metadata["per_row_rows"] = 0
    workspace = of(functions, workspace)
    q = assembly.assemble_positions(functions, t0, settings=settings.assembly,
                                    workspace=workspace)
    require_fully_driven(functions, t0, q, analysis, settings.assembly)
    times = output_times(t0, t_end, step)
    mapped = _MappedGrid(functions, settings, workspace)
    loads = Loads(functions)
    state, previous, done = np.concatenate([q, 0 * q, 0 * q]), t0, 0
    most = settings.max_block
    span = min(len(times), most)
    try:
        while done < len(times):
            cancel.poll()
            block = times[done:done + span]
            clock = time.perf_counter()
            states, lam, passed = mapped(state, previous, block)
            if time.perf_counter() - clock > BLOCK_SECONDS:  # bounded in wall time
                most = max(settings.min_block, len(block) // 2)
            result.extend(block[:passed], *np.split(states[:passed], 3, axis=1),
                          loads(block[:passed], states[:passed], lam[:passed]))
            done += passed
            if passed:
                state, previous = states[passed - 1], block[passed - 1]
            span = min(most, 2 * span if passed == len(block)
                       else max(settings.min_block, 2 * passed))
            if passed < len(block):  # the per-row code does (or reports) the rejected row
                state, lam_row = _per_row(functions, state, previous, times[done],
                                          settings.assembly)
                result.append(times[done], *np.split(state, 3),
                              loads(times[done:done + 1], state[None], lam_row[None])[0])
                result.metadata["per_row_rows"] += 1
                previous, done = times[done], done + 1
    except AnalysisError as error:
        error.partial = result
        raise
    finally:
        loads.record(result)
    return result


class Loads:
    """The load parts of joint frictions with `mu` (formulations/prescribed_friction.py;
    `loaded`: those frictions, by default all): a call takes a block's times, states
    [q, q_dot, q_ddot] (rows) and multipliers without them and returns the multipliers with
    them, keeping each friction's force for its results column (`record`:
    Result.fixed_columns)."""

    def __init__(self, functions: SystemFunctions, loaded: list | None = None):
        self.loaded = prescribed_friction.elements(functions.ir) if loaded is None else loaded
        self.forces = []
        if self.loaded:
            self.function = prescribed_friction.correction(functions, self.loaded)
            self.n = functions.ir.n_bodies * 7

    def __call__(self, times, states, lam):
        from casmech.runtime.load_checks import check_rows

        if not self.loaded or not len(times):
            return lam
        n = self.n
        mapped = self.function.map(len(times))
        lam, forces, loads = (np.array(v) for v in mapped(
            np.reshape(times, (1, -1)), states[:, :n].T, states[:, n:2 * n].T, lam.T))
        check_rows(times, self.loaded, loads.T)
        self.forces.append(forces.T)
        return lam.T

    def record(self, result: Result) -> None:
        if self.forces:
            forces = np.concatenate(self.forces)
            result.fixed_columns |= {f"{e.name}.friction": forces[:, i]
                                     for i, e in enumerate(self.loaded)}


def _per_row(functions: SystemFunctions, state: np.ndarray, previous: float, t: float,
             settings: Assembly = DEFAULT.assembly):
    """state_at t from the state [q; q_dot; q_ddot] at `previous`: (new state, lam)."""
    h = t - previous
    q, q_dot, q_ddot = np.split(state, 3)
    q, q_dot, q_ddot, lam = state_at(functions, t, q + h * q_dot + 0.5 * h * h * q_ddot,
                                     q_dot + h * q_ddot, settings)
    return np.concatenate([q, q_dot, q_ddot]), lam


class _MappedGrid:
    """The prescribed step mapped over blocks of output times, one Function per padded
    block length (kept in the workspace: a later analysis of the same system reuses them); a
    call returns the block's states, multipliers and how many leading rows passed the step's
    checks (|Phi| within the assembly tolerance, pivots above pivot_ratio)."""

    def __init__(self, functions: SystemFunctions, settings: KinematicsSolver,
                 workspace: Workspace):
        from casmech.formulations import prescribed

        self.step = prescribed.step(functions.functions)
        self.chunk, self.grid = prescribed.CHUNK, prescribed.grid
        self.m = functions.n_rows
        self.settings, self.workspace = settings, workspace

    def __call__(self, state, previous: float, block: np.ndarray):
        rows = len(block)
        padded = -(-rows // self.chunk) * self.chunk
        function = self.workspace.kept("prescribed_grids", padded, lambda: BufferedCall(
            self.grid(self.step, rows)[0]))
        times = np.concatenate([block, np.full(padded - rows, block[-1])])
        steps = np.diff(times, prepend=previous)
        states, checks = function(state, np.vstack([times, steps]))
        worst, ratio = checks[self.m, :rows], checks[self.m + 1, :rows]
        states, checks = states[:, :rows], checks[:, :rows]
        good = (worst <= self.settings.assembly.tolerance) & (ratio > self.settings.pivot_ratio)
        good &= np.isfinite(states).all(axis=0) & np.isfinite(checks).all(axis=0)
        passed = rows if good.all() else int(np.argmin(good))
        return states.T, checks[:self.m].T, passed


def run_assembly(functions: SystemFunctions, t0: float = 0.0, progress=None,
                 settings: Assembly = DEFAULT.assembly,
                 workspace: Workspace | None = None) -> Result:
    """One state at t0: assembled positions, velocities projected from the file's, and the
    accelerations and multipliers the equations of motion give at that instant."""
    result = Result("assembly", on_row=progress)
    q, q_dot = assembly.initial_state(functions, t0, settings, workspace)
    q_ddot, lam = assembly.solve_dynamic_accelerations(functions, t0, q, q_dot,
                                                       settings=settings, workspace=workspace)
    result.append(t0, q, q_dot, q_ddot, lam)
    return result
