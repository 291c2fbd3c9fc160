"""The results rows of the joint formulation's loop DAE (runtime.joint_dynamics), with the loop
closures' multipliers solved at each row's (t, x): the saddle system of the DAE at
acceleration level (formulations.joint_system.saddle_terms) by numerics.kkt.saddle, with the
rows the DAE masks turned into lam_k = P_k u_dot - gamma_k as the r-p DAE's rows are
(runtime.dae_rows.solve). Those multipliers then give the row's accelerations and every joint
row's multiplier through the joint system's results function, as the integrator's would. The
integrator's algebraic states are not read: IDAS interpolates them over its step and keeps
them out of its error test (docs/decisions/row-multipliers.md)."""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.formulations.joint_system import JointSystem
from casmech.numerics import kkt
from casmech.runtime import cancel, solver_messages
from casmech.runtime.assembly import saddle_solution
from casmech.runtime.buffers import ColumnCall


def solved_motion(terms: ca.Function, saddle: ca.Function, motion: ca.Function) -> ca.Function:
    """(t, x, w, signs) -> motion's (q, q_dot, q_ddot, lam) at z = [lam solved at (t, x) by
    `saddle` (numerics.kkt.saddle of the terms' patterns); mu = 0] (module docstring), w the
    DAE's row mask."""
    t, x = ca.MX.sym("t"), ca.MX.sym("x", terms.size1_in(1))
    m = terms.size1_out(1)
    w, signs = ca.MX.sym("w", m), ca.MX.sym("signs", motion.size1_in(3))
    mass, jacobian, forces, gamma = terms(t, x)
    _, lam = saddle(mass, jacobian, forces, gamma, w)
    outputs = motion(t, x, ca.vertcat(lam, ca.MX.zeros(m)), signs)
    return ca.Function("joint_solved_motion", [t, x, w, signs], outputs[:4],
                       ["t", "x", "w", "signs"], ["q", "q_dot", "q_ddot", "lam"])


class LoopRows:
    """The rows of one loop system: (q, q_dot, q_ddot, lam) per column of states, one mapped
    call; a column whose saddle matrix is singular (the LU meets a zero pivot) by
    runtime.assembly.saddle_solution's least squares."""

    def __init__(self, terms: ca.Function, system: JointSystem, mask: np.ndarray):
        self.terms = terms  # formulations.joint_system.saddle_terms (compiled or not)
        self.motion, self.mask = system.motion, np.asarray(mask, float)
        self.saddle = kkt.saddle(self.terms.sparsity_out(0), self.terms.sparsity_out(1))
        self.call = ColumnCall(solved_motion(self.terms, self.saddle, system.motion))

    def __call__(self, times: np.ndarray, states: np.ndarray, signs: np.ndarray):
        try:
            with solver_messages.without_input_dumps():
                return self.call(times[None, :], states, self.mask[:, None], signs[:, None])
        except RuntimeError as error:  # the LU met a zero pivot
            cancel.check(error)
        columns = [self.column(t, states[:, j], signs) for j, t in enumerate(times)]
        return tuple(np.column_stack(parts) for parts in zip(*columns, strict=True))

    def column(self, t: float, x: np.ndarray, signs: np.ndarray) -> list[np.ndarray]:
        """One row, its multipliers by saddle_solution (least squares where singular)."""
        mass, jacobian, forces, gamma = self.terms(t, x)
        _, lam = saddle_solution(self.saddle, mass, jacobian, forces,
                                 np.ravel(np.array(gamma)), self.mask)
        z = np.concatenate([lam, np.zeros(len(lam))])
        return [np.array(out.full()).ravel() for out in self.motion(t, x, z, signs)[:4]]
