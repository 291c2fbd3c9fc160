"""Kinematic analysis of a fully driven (0-DOF) mechanism, and inverse dynamics on top of it.

At each output time: positions by Newton from a second-order predictor, velocities from
Phi_q q_dot = nu, accelerations from Phi_q q_ddot = gamma; then the multipliers from the
equations of motion with the prescribed motion, Phi_q^T lam = Q - M q_ddot (inverse dynamics).
With a fully driven mechanism the two analyses differ only in what they are asked for; both
report the joint reactions, since the prescribed motion determines them.

The rows come from one mapped CasADi Function over the output grid (formulations.prescribed); a
row it rejects (Newton not converged in its fixed steps, or Phi_q close to losing rank) is
done by the per-row code (state_at: numpy least squares), which reports a failure with the
joints involved, and the mapped step resumes after it.
"""

from __future__ import annotations

import numpy as np

from casmech.equations.checks import structure
from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError, Diagnostic, ModelError
from casmech.formulations import prescribed
from casmech.runtime import assembly
from casmech.runtime.buffers import BufferedCall
from casmech.runtime.memo import kept
from casmech.runtime.results import Result

# Rows whose Phi_q has min |R_kk| / max |R_kk| below this go to the per-row code, which decides
# by the singular values whether the configuration is singular (that ratio bounds 1/cond from
# above, so the per-row code sees every row it could reject; numpy's rank cut is ~1e-14).
PIVOT_RATIO = 1e-10


def output_times(t0: float, t_end: float, step: float) -> np.ndarray:
    n = int(np.floor((t_end - t0) / step + 1e-9))
    times = t0 + step * np.arange(n + 1)
    return times if times[-1] >= t_end - 1e-9 * step else np.append(times, t_end)


def require_fully_driven(functions: SystemFunctions, t: float, q: np.ndarray,
                         analysis: str) -> None:
    report = structure(functions, t, q)
    if report.dof == 0:
        return
    raise ModelError([Diagnostic(
        "E501", "analysis.type",
        f"{analysis} needs a fully driven mechanism, but this one has {report.dof} "
        "degree(s) of freedom at the assembled configuration",
        functions.ir.analysis.source, expected="0 degrees of freedom", got=f"{report.dof}",
        hint="add drivers (`driver: {angle: ...}` on a revolute joint, `f:` on a basic "
             "constraint) or run a dynamics analysis")])


def state_at(functions: SystemFunctions, t: float, q_guess: np.ndarray, q_dot_guess: np.ndarray):
    q = assembly.newton(functions, t, q_guess)
    q_dot = assembly.solve_velocities(functions, t, q, q_dot_guess)
    q_ddot = assembly.solve_kinematic_accelerations(functions, t, q, q_dot)
    lam = assembly.solve_multipliers(functions, t, q, q_dot, q_ddot)
    return q, q_dot, q_ddot, lam


KEPT_GRIDS = 16  # mapped grids (one per padded block length) kept with the functions
MIN_SPAN = 16  # rows of the first mapped call after a row the per-row code had to do
# Most rows per mapped call: casadi builds a grid's nested mapaccum in time growing faster than
# its length, so long grids are called in blocks of this many rows through one kept Function
# (docs/decisions/output-blocks.md).
MAX_SPAN = 2048


def run_prescribed_motion(functions: SystemFunctions, t_end: float, step: float,
                          analysis: str = "kinematics", t0: float = 0.0,
                          progress=None) -> Result:
    """Rows by the mapped prescribed step over the grid in blocks of up to MAX_SPAN rows; after a
    row it rejects (done by state_at) it resumes over max(MIN_SPAN, twice the rows that last
    passed), doubling while they pass, so the mapped rows computed and discarded are at most
    twice those kept plus MIN_SPAN per rejected row. metadata per_row_rows: how many rows
    state_at did."""
    result = Result(analysis, on_row=progress)
    result.metadata["per_row_rows"] = 0
    q = assembly.assemble_positions(functions, t0)
    require_fully_driven(functions, t0, q, analysis)
    times = output_times(t0, t_end, step)
    mapped = _MappedGrid(functions)
    state, previous, done = np.concatenate([q, 0 * q, 0 * q]), t0, 0
    span = min(len(times), MAX_SPAN)
    try:
        while done < len(times):
            block = times[done:done + span]
            states, lam, passed = mapped(state, previous, block)
            result.extend(block[:passed], *np.split(states[:passed], 3, axis=1), lam[:passed])
            done += passed
            if passed:
                state, previous = states[passed - 1], block[passed - 1]
            span = min(MAX_SPAN, 2 * span if passed == len(block) else max(MIN_SPAN, 2 * passed))
            if passed < len(block):  # the per-row code does (or reports) the rejected row
                state, lam_row = _per_row(functions, state, previous, times[done])
                result.append(times[done], *np.split(state, 3), lam_row)
                result.metadata["per_row_rows"] += 1
                previous, done = times[done], done + 1
    except AnalysisError as error:
        error.partial = result
        raise
    return result


def _per_row(functions: SystemFunctions, state: np.ndarray, previous: float, t: float):
    """state_at t from the state [q; q_dot; q_ddot] at `previous`: (new state, lam)."""
    h = t - previous
    q, q_dot, q_ddot = np.split(state, 3)
    q, q_dot, q_ddot, lam = state_at(functions, t, q + h * q_dot + 0.5 * h * h * q_ddot,
                                     q_dot + h * q_ddot)
    return np.concatenate([q, q_dot, q_ddot]), lam


class _MappedGrid:
    """The prescribed step mapped over blocks of output times, one Function per padded
    block length; a call returns the block's states, multipliers and how many leading rows
    passed the step's checks."""

    def __init__(self, functions: SystemFunctions):
        self.step = prescribed.step(functions.functions)
        self.m = functions.n_rows
        # kept with the functions: a later analysis of the same system reuses the mapped grids
        self.grids: dict[int, object] = functions.derived.setdefault("prescribed_grids", {})

    def __call__(self, state, previous: float, block: np.ndarray):
        rows = len(block)
        padded = -(-rows // prescribed.CHUNK) * prescribed.CHUNK
        function = kept(self.grids, padded,
                        lambda: BufferedCall(prescribed.grid(self.step, rows)[0]), KEPT_GRIDS)
        times = np.concatenate([block, np.full(padded - rows, block[-1])])
        steps = np.diff(times, prepend=previous)
        states, checks = function(state, np.vstack([times, steps]))
        worst, ratio = checks[self.m, :rows], checks[self.m + 1, :rows]
        states, checks = states[:, :rows], checks[:, :rows]
        good = (worst <= assembly.POSITION_TOLERANCE) & (ratio > PIVOT_RATIO)
        good &= np.isfinite(states).all(axis=0) & np.isfinite(checks).all(axis=0)
        passed = rows if good.all() else int(np.argmin(good))
        return states.T, checks[:self.m].T, passed


def run_assembly(functions: SystemFunctions, t0: float = 0.0, progress=None) -> Result:
    """One state at t0: assembled positions, velocities projected from the file's, and the
    accelerations and multipliers the equations of motion give at that instant."""
    result = Result("assembly", on_row=progress)
    q, q_dot = assembly.initial_state(functions, t0)
    q_ddot, lam = assembly.solve_dynamic_accelerations(functions, t0, q, q_dot)
    result.append(t0, q, q_dot, q_ddot, lam)
    return result
