"""What CasADi derives from phi, written once for any symbols: one row's (a kernel of
equations.row_kernels) or a whole system's.

phi_q = d phi / d q, nu = -phi_t, gamma = -(phi_q q_dot)_q q_dot - 2 phi_qt q_dot - phi_tt;
the r-omega form's gamma_hat; the reaction of rows on a body (Haug 1989; the ME751 lecture).
Ground's pose, GROUND_POSE, is what its constant frame is in every kernel.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping

import casadi as ca
import numpy as np

from casmech.core import euler

GROUND_POSE = np.array([0.0, 0, 0, 1, 0, 0, 0])


def of_phi(phi, q, t, q_dot) -> dict[str, ca.SX]:
    """Phi_q, nu, gamma of phi(t, q) by AD, for any symbols q, t, q_dot."""
    phi_q = ca.jacobian(phi, q)
    nu = -ca.jacobian(phi, t)
    return {"phi_q": phi_q, "nu": nu, "gamma": gamma_of(phi_q, nu, q, t, q_dot)}


class Derived(Mapping):
    """phi and what of_phi derives from it, each derivative taken when first read (the same
    expressions as of_phi's): a run that reads phi and nu alone never builds phi_q's graph nor
    gamma's second derivatives. `gamma`: whether gamma is one of the keys."""

    def __init__(self, phi, q, t, q_dot, gamma: bool = True):
        self._values: dict[str, ca.SX] = {"phi": phi}
        self._q, self._t, self._q_dot = q, t, q_dot
        self._keys = ("phi_q", "nu", "gamma", "phi") if gamma else ("phi_q", "nu", "phi")

    def __getitem__(self, key: str) -> ca.SX:
        if key not in self._keys:
            raise KeyError(key)
        if key not in self._values:
            self._values[key] = self._derive(key)
        return self._values[key]

    def _derive(self, key: str) -> ca.SX:
        phi, q, t = self._values["phi"], self._q, self._t
        if key == "phi_q":
            return ca.jacobian(phi, q)
        if key == "nu":
            return -ca.jacobian(phi, t)
        return gamma_of(self["phi_q"], self["nu"], q, t, self._q_dot)

    def __iter__(self) -> Iterator[str]:
        return iter(self._keys)

    def __len__(self) -> int:
        return len(self._keys)


def gamma_of(phi_q, nu, q, t, q_dot) -> ca.SX:
    """gamma = -(Phi_q q_dot)_q q_dot - 2 Phi_qt q_dot - Phi_tt (Phi_t = -nu)."""
    phi_q_qdot = phi_q @ q_dot
    return (-ca.jacobian(phi_q_qdot, q) @ q_dot - 2 * ca.jacobian(phi_q_qdot, t)
            - ca.jacobian(-nu, t))


def gamma_hat(jacobian, nu, v, q, q_dot, t):
    """-d/dt (jacobian v - nu) along q_dot(q, v) at constant v: the r-omega acceleration
    constraint's right-hand side (rows of [Phi_r, Pi_bar] over q and t)."""
    c = jacobian @ v - nu
    return -(ca.jacobian(c, q) @ q_dot + ca.jacobian(c, t))


def reaction(phi, lam, r_j, p_j, about) -> tuple:
    """(force, torque) that the rows phi (with multipliers lam) exert on body j (CM r_j, Euler
    parameters p_j), global, the torque about the point `about`.

    From the lecture: force -Phi_r_j^T lam, body-frame torque about the CM -Pi_bar_j^T lam,
    moved to the point P: T_P = A_j n_bar + (r_j - r_P) x F.
    """
    return reaction_of_blocks(ca.jacobian(phi, r_j), ca.jacobian(phi, p_j), lam, r_j, p_j, about)


def reaction_of_blocks(phi_r, phi_p, lam, r_j, p_j, about) -> tuple:
    """reaction's (force, torque) from the rows' Jacobian blocks Phi_r_j, Phi_p_j."""
    force = -phi_r.T @ lam
    n_bar = -0.5 * euler.g_matrix(p_j) @ phi_p.T @ lam
    return force, euler.rotation(p_j) @ n_bar + ca.cross(r_j - about, force)
