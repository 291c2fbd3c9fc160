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
def tree_multipliers(block, rotation, wrench, pivots=None):
    """A tree joint's row multipliers from its constraint wrench on the child (CM frame):
    -B^T lam = the wrench f (global force, body-frame torque), B the rows' r-omega Jacobian at
    the child, solved in the least-squares sense: B B^T lam = -B f, B B^T (symmetric positive
    definite: a joint's rows are independent) factored by Cholesky, about half the
    instructions of a general solve. With `pivots` (translation_pivots: three rows whose
    translation columns are one +-1 each, the other rows' none), the three force equations
    give those rows' multipliers at once and the torque equations the others' in the
    least-squares sense (B_w B_w^T of those rows alone): the same multipliers for a wrench the
    rows can exert (a constraint wrench), with a fraction of the arithmetic."""
    force = ca.vertcat(rotation @ wrench[3:6], wrench[0:3])
    if pivots is None:
        upper = ca.chol(block @ block.T)  # B B^T = R^T R
        return (-ca.solve(upper, ca.solve(upper.T, block @ force)),)
    lam = [None] * block.size1()
    for row, column, sign in pivots:  # sign lam_row = -f_column
        lam[row] = -sign * force[column]
    held = [row for row, _, _ in pivots]
    torque = -force[3:6] - block[held, 3:6].T @ ca.vertcat(*(lam[row] for row in held))
    others = [row for row in range(block.size1()) if lam[row] is None]
    if others:  # B_w^T lam = torque over the other rows, by the normal equations
        turning = block[others, 3:6]
        upper = ca.chol(turning @ turning.T)
        for row, value in zip(others, ca.vertsplit(
                ca.solve(upper, ca.solve(upper.T, turning @ torque))), strict=True):
            lam[row] = value
    return (ca.vertcat(*lam),)


def translation_pivots(block) -> tuple | None:
    """((row, column, sign), ...) of the three rows of a joint's r-omega Jacobian `block` (SX)
    whose translation columns hold one constant +-1 each (the rest constant zeros), in
    distinct columns, where no other row has a translation entry (a point held fixed to the
    child, as a revolute, universal, spherical or fixed joint's rows hold it); else None.
    tree_multipliers' fast path."""
    sparsity, pivots = block.sparsity(), []
    for row in range(block.size1()):
        columns = [c for c in range(3) if sparsity.has_nz(row, c) and not (
            block[row, c].is_constant() and float(block[row, c]) == 0.0)]
        if not columns:
            continue
        entry = block[row, columns[0]]
        if len(columns) > 1 or not entry.is_constant() or abs(float(entry)) != 1.0:
            return None
        pivots.append((row, columns[0], float(entry)))
    return tuple(pivots) if sorted(c for _, c, _ in pivots) == [0, 1, 2] else None


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
