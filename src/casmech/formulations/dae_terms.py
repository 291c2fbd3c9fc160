"""The terms of the DAE residuals (formulations.dae), written once for one element
(formulations.residual_kernels builds every joint's, body's and force element's from them).
P_s, phi_s, ...: the rows already scaled by their s (or s_phi)."""

from __future__ import annotations

import casadi as ca


def scaled(matrix, s):
    """diag(s) matrix."""
    return matrix * ca.repmat(s, 1, matrix.size2())


def constraint_forces(p_s, lam):
    """P_s^T lam."""
    return p_s.T @ lam


def dynamics(mass, v_dot, p_s, lam, forces):
    """M v_dot + P_s^T lam - F."""
    return mass @ v_dot + constraint_forces(p_s, lam) - forces


def acceleration_rows(p_s, v_dot, gamma_s, w, lam):
    """P_s v_dot - gamma_s - w lam (projection)."""
    return p_s @ v_dot - gamma_s - w * lam


def position_rows(phi_s, w_phi, mu):
    """(1 - w) phi_s - w mu (ggl)."""
    return (1 - w_phi) * phi_s - w_phi * mu


def velocity_rows(p_s, v, nu_s, w, lam):
    """(1 - w) (P_s v - nu_s) - w lam (ggl)."""
    return (1 - w) * (p_s @ v - nu_s) - w * lam


def ggl_q_dot(q_dot, phi_q_s, mu):
    """q_dot + Phi_q_s^T mu (ggl)."""
    return q_dot + constraint_forces(phi_q_s, mu)
