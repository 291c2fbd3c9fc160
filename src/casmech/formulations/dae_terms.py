"""The DAE residual (formulations.dae), written once over what it is made of: the whole model's
matrices (the inline residual, formulations.dae) or one element's blocks (a joint's rows, a body,
a force element: formulations.residual_kernels, whose sum over the elements is the same residual).

    ode: [q_dot (+ Phi_q_s^T mu, ggl);  v_dot]
    alg: [M v_dot + P_s^T lam - F;  rows]
    rows: P_s v_dot - gamma_s - w lam (projection)
          (1 - w_phi) phi_s - w_phi mu;  (1 - w) (P_s v - nu_s) - w lam (ggl)

P_s, phi_s, ...: the rows already scaled by their s (or s_phi). Every part is optional: an element
has only some (a joint no M, F or q_dot; a force element only F)."""

from __future__ import annotations

import casadi as ca

from casmech.core.records import record


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


@record
class Rows:
    """Constraint rows of a residual: P_s (over v) with its multipliers lam, masks w and
    gamma_s (projection) or nu_s (ggl); for ggl also Phi's rows phi_s, Phi_q_s (over q), their
    masks w_phi and multipliers mu (r-omega: Phi has rows P has not)."""

    p_s: object
    lam: object
    w: object
    gamma_s: object = None
    nu_s: object = None
    phi_s: object = None
    phi_q_s: object = None
    w_phi: object = None
    mu: object = None


@record
class Parts:
    """What a residual (or one element of it) is made of; None: the part is absent."""

    v: object = None  # the velocities (ggl's velocity rows)
    q_dot: object = None  # q_dot(q, v)
    v_dot: object = None
    mass: object = None
    forces: object = None
    rows: Rows | None = None


def residual(parts: Parts, kind: str) -> list:
    """[ode_q, ode_v, alg_v, alg_rows] of the residual (module docstring), each None where the
    parts give nothing to it; kind: "projection" or "ggl"."""
    rows = parts.rows
    ode_q = parts.q_dot
    if rows is not None and kind == "ggl":
        ode_q = constraint_forces(rows.phi_q_s, rows.mu) if ode_q is None else \
            ggl_q_dot(ode_q, rows.phi_q_s, rows.mu)
    alg_v = None
    if parts.mass is not None:
        alg_v = parts.mass @ parts.v_dot - parts.forces if rows is None else \
            dynamics(parts.mass, parts.v_dot, rows.p_s, rows.lam, parts.forces)
    elif rows is not None:
        alg_v = constraint_forces(rows.p_s, rows.lam)
        alg_v = alg_v if parts.forces is None else alg_v - parts.forces
    elif parts.forces is not None:
        alg_v = -parts.forces
    alg_rows = None
    if rows is not None:
        alg_rows = ca.vertcat(position_rows(rows.phi_s, rows.w_phi, rows.mu),
                              velocity_rows(rows.p_s, parts.v, rows.nu_s, rows.w, rows.lam)) \
            if kind == "ggl" else acceleration_rows(rows.p_s, parts.v_dot, rows.gamma_s, rows.w,
                                                    rows.lam)
    ode_v = parts.v_dot if parts.q_dot is not None else None
    return [ode_q, ode_v, alg_v, alg_rows]
