"""The output rows of the r-p / r-omega DAE runs (runtime.dynamics) for a block of states, each by
mapped casadi.Function calls: the accelerations and multipliers solved at each row's state, the
drift check (index-1 DAE only) and the results' r-p rates and multipliers. The Functions and
their maps are kept in the run's workspace (runtime.workspace), so a later run builds none of
them."""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.equations.functions import SystemFunctions
from casmech.formulations import dae
from casmech.formulations.table import BODY_FORMS
from casmech.numerics import kkt
from casmech.runtime.buffers import ColumnCall
from casmech.runtime.results import Result
from casmech.runtime.workspace import Workspace, of


def mapped(function: ca.Function, *columns, workspace: Workspace | None = None
           ) -> list[np.ndarray]:
    """`function` evaluated at every column of its arguments (mapped calls in blocks:
    runtime.buffers.ColumnCall); every output as a 2-D array with one column per evaluation.
    `workspace` keeps the ColumnCall per function (by the Function itself: casadi.Functions
    hash by identity and the entry holds it)."""
    count = max(np.shape(c)[1] for c in columns)
    if workspace is None:
        call = ColumnCall(function)
    else:
        call = workspace.kept("dae_row_maps", function, lambda: ColumnCall(function))
    return [np.asarray(out).reshape(-1, count) for out in call(*columns)]


def minimum_norm(jacobian, lam, keep: list[int]):
    """The multipliers of least norm giving the same generalized force jacobian^T lam, for a
    jacobian whose rows outside `keep` depend on the rows in it: lam* = C (C^T C)^-1 y, with
    jacobian = C jacobian_S (C = jacobian jacobian_S^T (jacobian_S jacobian_S^T)^-1) and
    jacobian_S^T y = jacobian^T lam (lam* lies in the range of C, the least-norm solutions'
    space; non-singular solves only, so it maps over rows)."""
    kept_rows = jacobian[keep, :]
    gram = kept_rows @ kept_rows.T
    y = ca.solve(gram, kept_rows @ (jacobian.T @ lam), "qr")
    c = ca.solve(gram, kept_rows @ jacobian.T, "qr").T
    return c @ ca.solve(c.T @ c, y, "qr")


def solve(f: SystemFunctions, name: str) -> ca.Function:
    """(t, q, v, w, s) -> (v_dot, lam / s): the equations of motion's linear part
    [M P_s^T; P_s -diag(w)] [v_dot; lam / s] = [F; gamma_s] solved at one state
    (numerics.kkt.saddle inlined; P_s = diag(s) P, gamma_s = s * gamma, as the DAE scales
    them: formulations.dae). A row's v_dot and lam come from here, not from the integrator's
    algebraic states: those are interpolated over IDAS's step and kept out of its error test,
    so they are neither as accurate as the state nor right after a force's jump within a
    step (a Coulomb friction's reversal on a driven joint)."""
    form = BODY_FORMS[name]
    n_q, n_v, m = dae.sizes(f.functions, name)
    t, q, v = ca.MX.sym("t"), ca.MX.sym("q", n_q), ca.MX.sym("v", n_v)
    w, s = ca.MX.sym("w", m), ca.MX.sym("s", m)
    mass, jacobian = f[form.mass](q), f[form.jacobian](t, q) * ca.repmat(s, 1, n_v)
    saddle = kkt.saddle(mass.sparsity(), jacobian.sparsity())
    v_dot, lam = saddle(mass, jacobian, f[form.forces](t, q, v), f[form.gamma](t, q, v) * s, w)
    return ca.Function(f"row_accelerations_{name}", [t, q, v, w, s], [v_dot, lam],
                       ["t", "q", "v", "w", "s"], ["v_dot", "lam"])


def _functions(f: SystemFunctions, name: str, sizes: tuple[int, int, int],
               mask: np.ndarray) -> tuple[ca.Function, ca.Function]:
    """(result_rows, drift) of formulation `name` with the rows `mask` drops."""
    form = BODY_FORMS[name]
    n_q, n_v, m = sizes
    t, q, v = ca.MX.sym("t"), ca.MX.sym("q", n_q), ca.MX.sym("v", n_v)
    v_dot, multipliers = ca.MX.sym("v_dot", n_v), ca.MX.sym("lam", m)
    lam, n = multipliers, f.n_joint_rows
    if mask.any():  # joint rows: [Phi_r, Pi_bar], the same in both formulations
        keep = [k for k in range(n) if not mask[k]]
        lam = ca.vertcat(minimum_norm(f["romega_jacobian"](t, q), lam[:n], keep), lam[n:])
    if form.q_dot is None:
        q_dot, q_ddot = v, v_dot
    else:  # normalization rows carry no reaction
        (q_dot, q_ddot), lam = f["romega_to_rp"](q, v, v_dot), ca.vertcat(
            lam, ca.MX(f.n_rows - m, 1))
    rates = ca.Function(f"result_rows_{name}", [t, q, v, v_dot, multipliers],
                        [q_dot, q_ddot, lam])
    phi = f["phi"](t, q)
    velocity = f[form.jacobian](t, q) @ v - f[form.nu](t, q)
    drift = ca.Function(f"drift_{name}", [t, q, v], [
        ca.mmax(ca.fabs(phi)) if phi.numel() else ca.MX(1, 1),
        ca.mmax(ca.fabs(velocity)) if velocity.numel() else ca.MX(1, 1)])
    return rates, drift


class Rows:
    """The rows of one run: formulation `name` with sizes (n_q, n_v, rows of P), the rows
    `mask` drops, the drift tolerance and the output step."""

    def __init__(self, functions: SystemFunctions, name: str, sizes: tuple[int, int, int],
                 mask: np.ndarray, tolerance: float, step: float,
                 workspace: Workspace | None = None):
        self.n_q, self.n_v = sizes[:2]
        self.tolerance, self.step = tolerance, step
        self.workspace = of(functions, workspace)
        key = (name, np.asarray(mask, bool).tobytes())
        self.rates, self.drift = self.workspace.kept("dae_rows", key, lambda: _functions(
            functions, name, sizes, mask))

    def split(self, states: np.ndarray):
        n_q, n_v = self.n_q, self.n_v
        return states[:n_q], states[n_q:n_q + n_v], states[n_q + n_v:]

    def first_drifted(self, times: np.ndarray, states: np.ndarray) -> int | None:
        """The first column where |Phi| passed the tolerance, or the velocity-constraint
        residual passed what would move the positions by as much before the next output."""
        q, v, _ = self.split(states)
        phi, velocity = mapped(self.drift, times[None, :], q, v, workspace=self.workspace)
        drifted = (phi[0] > self.tolerance) | (velocity[0] * self.step > self.tolerance)
        return int(np.argmax(drifted)) if drifted.any() else None

    def rows(self, times: np.ndarray, states: np.ndarray, multipliers: np.ndarray):
        """(q, q_dot, q_ddot, lam), one row per time: r-p velocities and accelerations, every
        multiplier (the least-norm ones where rows were dropped; 0 for r-omega's
        normalization rows)."""
        q, v, v_dot = self.split(states)
        q_dot, q_ddot, lam = mapped(self.rates, times[None, :], q, v, v_dot, multipliers,
                                    workspace=self.workspace)
        return q.T, q_dot.T, q_ddot.T, lam.T

    def record(self, result: Result, times: np.ndarray, states: np.ndarray,
               multipliers: np.ndarray) -> None:
        """Appends the rows."""
        result.extend(times, *self.rows(times, states, multipliers))
