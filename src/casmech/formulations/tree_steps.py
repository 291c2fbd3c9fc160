"""The per-joint and per-body steps of a tree's results rows, written once: traced per structure
by the unrolled build (formulations/joint_system.py) and built into the mapped tree's kernels
(formulations/mapped_rows.py)."""

from __future__ import annotations

import casadi as ca

from casmech.core import euler
from casmech.core.traced_steps import traced
from casmech.equations import body


@traced
def relative_step(r_p, p_p, r_p_dot, p_p_dot, r_c, p_c, r_c_dot, p_c_dot, c_p, s_p, c_c, s_c):
    """(rotation, gap, twist) of one tree joint from its bodies' r-p states (JointSystem's
    relative_states)."""
    a_p, a_c = euler.rotation(p_p), euler.rotation(p_c)
    w_p, w_c = body.angular_velocity(p_p, p_p_dot), body.angular_velocity(p_c, p_c_dot)
    o_p, o_c = r_p + a_p @ s_p, r_c + a_c @ s_c
    o_p_dot = r_p_dot + a_p @ ca.cross(w_p, s_p)
    o_c_dot = r_c_dot + a_c @ ca.cross(w_c, s_c)
    rotation = c_p.T @ a_p.T @ a_c @ c_c
    gap = a_p.T @ (o_c - o_p)
    omega = c_c.T @ (w_c - a_c.T @ a_p @ w_p)
    gap_dot = c_p.T @ (a_p.T @ (o_c_dot - o_p_dot) - ca.cross(w_p, gap))
    return rotation, c_p.T @ gap, ca.vertcat(omega, rotation.T @ gap_dot)


@traced
def tree_multipliers(block, rotation, wrench):
    """A tree joint's row multipliers from its constraint wrench on the child (CM frame):
    -B^T lam = the wrench (global force, body-frame torque), B the rows' r-omega Jacobian at
    the child, solved in the least-squares sense: B B^T lam = -B f, B B^T (symmetric positive
    definite: a joint's rows are independent) factored by Cholesky, about half the
    instructions of a general solve."""
    force = ca.vertcat(rotation @ wrench[3:6], wrench[0:3])
    upper = ca.chol(block @ block.T)  # B B^T = R^T R
    return (-ca.solve(upper, ca.solve(upper.T, block @ force)),)


@traced
def body_rates(sign, p, rotation, velocity, acceleration):
    """A body's results-row (p, p_dot, r_ddot, p_ddot), its Euler parameters times sign, from
    its CM-frame spatial velocity and acceleration."""
    p = sign * p
    omega, alpha = velocity[0:3], acceleration[0:3]
    r_ddot = rotation @ (acceleration[3:6] + ca.cross(omega, velocity[3:6]))
    p_dot = body.p_dot(p, omega)
    p_ddot = 0.5 * (euler.g_matrix(p_dot).T @ omega + euler.g_matrix(p).T @ alpha)
    return p, p_dot, r_ddot, p_ddot
