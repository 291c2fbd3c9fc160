"""The results rows of the joint formulation's loop DAE (runtime.joint_dynamics), with the loop
closures' multipliers solved at each row's (t, x): the saddle system of the DAE at
acceleration level (formulations.joint_system.saddle_terms) solved by
numerics.kkt.solve_saddle, with the rows the DAE masks turned into lam_k = P_k u_dot - gamma_k
as the r-p DAE's rows are (runtime.dae_rows.solve). Those multipliers then give the row's
accelerations and every joint row's multiplier through the joint system's results function, as
the integrator's would. The terms, the solve and the results function are one SX graph
(solved_motion), compiled with the motion in a compiled bundle's joint library. The
integrator's algebraic states are not read: IDAS interpolates them over its step and keeps
them out of its error test (docs/decisions/row-multipliers.md)."""

from __future__ import annotations

from collections.abc import Callable
from contextlib import nullcontext

import casadi as ca
import numpy as np

from casmech.numerics import kkt
from casmech.runtime import cancel, solver_messages
from casmech.runtime.assembly import saddle_solution
from casmech.runtime.buffers import ColumnCall
from casmech.runtime.nonfinite import all_finite
from casmech.runtime.row_calls import over_rows, rows_of


def solved_motion(terms: ca.Function, motion: ca.Function) -> ca.Function:
    """(t, x, w, signs) -> motion's (q, q_dot, q_ddot, lam) at z = [lam solved at (t, x) from
    the saddle terms by numerics.kkt.solve_saddle; mu = 0], w the DAE's row mask: one SX
    Function where terms and motion are SX Functions (formulations.joint_system's: inlined,
    their common subexpressions, the tree's kinematics, evaluated once), else one MX Function
    calling them (a parametric library's motion, bound to its model data) with the LU solve."""
    sym = ca.SX if terms.is_a("SXFunction") and motion.is_a("SXFunction") else ca.MX
    t, x = sym.sym("t"), sym.sym("x", terms.size1_in(1))
    m = terms.size1_out(1)
    w, signs = sym.sym("w", m), sym.sym("signs", motion.size1_in(3))
    mass, jacobian, forces, gamma = terms(t, x)
    _, lam = kkt.solve_saddle(mass, jacobian, forces, gamma, w)
    outputs = list(motion(t, x, ca.vertcat(lam, sym.zeros(m)), signs)[:4])
    return ca.Function("joint_solved_motion", [t, x, w, signs],
                       ca.cse(outputs) if sym is ca.SX else outputs,
                       ["t", "x", "w", "signs"], ["q", "q_dot", "q_ddot", "lam"])


class LoopRows:
    """The rows of one loop system: (q, q_dot, q_ddot, lam) per column of states, one call of
    `rows` (solved_motion's, compiled or not) over them all (over_rows); a column whose saddle
    matrix is singular (the solve's outputs not finite at a finite state) by
    runtime.assembly.saddle_solution's least squares, from the saddle terms `terms()` builds
    (called for the first such column only)."""

    def __init__(self, rows: ca.Function, terms: Callable[[], ca.Function],
                 motion: ca.Function, mask: np.ndarray):
        self.call, self.terms, self.motion = over_rows(rows), terms, motion
        # CasADi's map prints a failed evaluation's inputs before raising (held back); the
        # rows' C loop prints nothing, its failure is its own RuntimeError
        self._quiet = solver_messages.without_input_dumps if type(self.call) is ColumnCall \
            else nullcontext
        self.mask = np.asarray(mask, float)
        self._saddle: tuple[ca.Function, ca.Function] | None = None

    def __call__(self, times: np.ndarray, states: np.ndarray, signs: np.ndarray):
        return tuple(row.T for row in self.by_row(times, states, signs))

    def by_row(self, times: np.ndarray, states: np.ndarray, signs: np.ndarray):
        """The same rows, one row per time (len(times) x n each): the rows' C loop's own
        layout."""
        try:
            with self._quiet():
                rows = rows_of(self.call, times, states.T, self.mask, signs)
        except RuntimeError as error:  # an evaluation that failed: every column alone
            cancel.check(error)
            rows = tuple(np.full((len(times), self.motion.size1_out(k)), np.nan)
                         for k in range(4))
        if all_finite(rows[2], rows[3]):  # every column solved (else column by column below)
            return rows
        solved = np.all(np.isfinite(rows[2]), axis=1) & np.all(np.isfinite(rows[3]), axis=1)
        for j in np.flatnonzero(~solved & np.all(np.isfinite(states), axis=0)):
            for row, value in zip(rows, self.column(times[j], states[:, j], signs), strict=True):
                row[j, :] = value
        return rows

    def column(self, t: float, x: np.ndarray, signs: np.ndarray) -> list[np.ndarray]:
        """One row, its multipliers by saddle_solution (least squares where singular)."""
        if self._saddle is None:
            terms = self.terms()
            self._saddle = terms, kkt.saddle(terms.sparsity_out(0), terms.sparsity_out(1))
        terms, saddle = self._saddle
        mass, jacobian, forces, gamma = terms(t, x)
        _, lam = saddle_solution(saddle, mass, jacobian, forces, np.ravel(np.array(gamma)),
                                 self.mask)
        z = np.concatenate([lam, np.zeros(len(lam))])
        return [np.array(out.full()).ravel() for out in self.motion(t, x, z, signs)[:4]]
