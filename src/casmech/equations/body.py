"""The terms of ONE rigid body in Euler parameters p (Haug 1989, ch. 11), written once.

equations.body_kernels and equations.row_kernels wrap them in the builder's kernels
(formulations.residual_kernels: the DAE's); the joint formulation calls them too.
Arguments are CasADi expressions (SX, or DM constants): r, r_dot the CM's position and velocity,
p, p_dot, p_ddot the Euler parameters and their rates, omega_bar the body-frame angular
velocity, inertia J_bar (3 x 3, body frame), mass m, gravity g.
"""

from __future__ import annotations

import casadi as ca

from casmech.core import euler


def normalization(p):
    """p^T p - 1: the Euler parameters' normalization constraint."""
    return p.T @ p - 1


def mass_block(p, inertia):
    """4 G^T J_bar G: the rotational block of the r-p mass matrix."""
    g = euler.g_matrix(p)
    return 4 * g.T @ inertia @ g


def quadratic_velocity(p, p_dot, inertia):
    """8 G_dot^T J_bar G_dot p (G_dot = G(p_dot)): the r-p quadratic velocity force."""
    g_dot = euler.g_matrix(p_dot)
    return 8 * g_dot.T @ inertia @ g_dot @ p


def angular_velocity(p, p_dot):
    """omega_bar = 2 G(p) p_dot (body frame)."""
    return 2 * euler.g_matrix(p) @ p_dot


def global_rates(p, *p_rates) -> list:
    """2 E(p) p_rate for each rate: the global angular velocity from p_dot, its acceleration
    from p_ddot (E(p) formed once)."""
    e = euler.e_matrix(p)
    return [2 * e @ rate for rate in p_rates]


def kinetic_energy(mass, inertia, r_dot, p, p_dot):
    """1/2 m r_dot.r_dot + 1/2 omega_bar^T J_bar omega_bar."""
    w_bar = angular_velocity(p, p_dot)
    return 0.5 * mass * (r_dot.T @ r_dot) + 0.5 * w_bar.T @ inertia @ w_bar


def gravity_potential(mass, gravity, r):
    """-m g.r."""
    return -(mass * (gravity.T @ r))


def p_dot(p, omega_bar):
    """p_dot = 1/2 G(p)^T omega_bar (the r-omega kinematic equation)."""
    return 0.5 * euler.g_matrix(p).T @ omega_bar


def moment(p, q_p):
    """n_bar = 1/2 G(p) Q_p: the body-frame torque of a generalized force Q_p on p (virtual
    work with delta p = 1/2 G^T delta pi_bar)."""
    return 0.5 * euler.g_matrix(p) @ q_p


def gyroscopic(omega_bar, inertia):
    """omega_bar~ J_bar omega_bar."""
    return ca.cross(omega_bar, inertia @ omega_bar)


def romega_torque(p, q_p, w, inertia):
    """n_bar - omega_bar~ J_bar omega_bar of one body, n_bar = 1/2 G Q_p (the r-omega form)."""
    return moment(p, q_p) - gyroscopic(w, inertia)


def q_ddot(q_dot, q, v, v_dot):
    """The time derivative of q_dot(q, v) (one body's p_dot(p, omega_bar), or a system's)."""
    return ca.jacobian(q_dot, q) @ q_dot + ca.jacobian(q_dot, v) @ v_dot


def pi_bar(phi_p, p):
    """Pi_bar = 1/2 Phi_p G(p)^T: a constraint's variation with respect to delta pi_bar."""
    return 0.5 * phi_p @ euler.g_matrix(p).T
