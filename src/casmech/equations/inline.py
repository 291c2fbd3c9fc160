"""The constraint rows and their derivatives in the inline evaluation: every body's frame
[r, A(p)] built once, every row's phi expanded from its kernel over those frames
(equations.row_kernels.phi_of_frames) into one SX graph, then differentiated as a whole by
CasADi (equations.derivatives). The mapped evaluation differentiates inside each kernel
instead: the same derivatives of the same phi (the chain rule commutes with the gather), where
AD of the whole graph shares each body's rotation derivatives between its rows. Per-body steps
(a frame, G^T, a joint's reaction from its Jacobian blocks) are traced once and evaluated on
each body's SX (core.traced_steps): no Python-level SX operation per body. The Jacobians keep the
entries AD gives (some are the constant 0), so that the integrators see the patterns, and give
the results, they always have.
"""

from __future__ import annotations

import casadi as ca

from casmech.core import euler
from casmech.core.traced_steps import traced
from casmech.core.values import constant
from casmech.equations import derivatives
from casmech.equations import row_kernels as kernels
from casmech.equations.derivatives import GROUND_POSE
from casmech.equations.evaluation import Evaluation
from casmech.equations.layout import Layout, ordered
from casmech.model.ir import GROUND_INDEX, ModelIR


def _frame(r, p):
    return (ca.vertcat(r, ca.vec(euler.rotation(p))),)


def _g_transpose(p):
    return (euler.g_matrix(p).T,)


FRAME, G_TRANSPOSE = traced(_frame), traced(_g_transpose)  # per-body steps
REACTION = traced(derivatives.reaction_of_blocks)  # per joint


def frames(ir: ModelIR, q, ground=None):
    """(12 x nb + 1): every body's [r; A(p)], then ground's (constant, or of the symbols
    `ground`)."""
    nb = ir.n_bodies
    columns = [FRAME(*_pose(q, nb, None, k))[0] for k in range(nb)]
    pose = ca.DM(GROUND_POSE) if ground is None else ground
    columns.append(_frame(pose[:3], pose[3:])[0] if ground is not None
                   else ca.DM(ca.vertcat(pose[:3], ca.vec(ca.DM.eye(3)))))
    return ca.horzcat(*columns)


def phi(ir: ModelIR, ev: Evaluation, groups: list, t, q, scale=None, ground=None,
        every=None):
    """phi (joint rows, then p^T p - 1 per body); ground's pose the symbols `ground` (7) or the
    constant GROUND_POSE; `every`: frames(ir, q, ground) when already built."""
    every = frames(ir, q, ground) if every is None else every
    nb = ir.n_bodies
    parts, order = [], []
    for group in groups:
        chosen = [nb if b == GROUND_INDEX else b for _, p in group.members for b in p.bodies]
        gathered = ca.reshape(every[:, chosen], kernels.FRAME * group.key.bodies, group.count)
        kernel = kernels.phi_of_frames(group.key, ground is not None)
        parts.append(group.call(kernel, gathered, group.c, group.f(t, scale))[0].T)
        order += group.rows
    m = len(ir.primitives)
    if nb:
        norm = ev.call(kernels.normalization()[0], nb, Layout(nb).p(q))[0]
        parts.append(norm.T)
        order += list(range(m, m + nb))
    return ordered(parts, order, ca.SX)


def grounded(ir: ModelIR, ev: Evaluation, groups: list, t, q) -> tuple:
    """(phi with ground's pose symbolic, those 7 symbols, the frames): the rows the unscaled
    constraints (ground fixed) and the reactions (differentiated with respect to ground)
    share."""
    ground = ca.SX.sym("q_ground", 7)
    every = frames(ir, q, ground)
    return phi(ir, ev, groups, t, q, ground=ground, every=every), ground, every


def constraints(ir: ModelIR, ev: Evaluation, groups: list, t, q, q_dot=None,
                scale=None, shared=None) -> derivatives.Derived:
    """phi, phi_q, nu and (given q_dot) gamma by AD of the whole phi, each derivative when
    first read (derivatives.Derived); `shared`: grounded's output (unscaled rows only)."""
    if scale is None:
        rows, ground, _ = shared or grounded(ir, ev, groups, t, q)
        value = ca.substitute(rows, ground, ca.DM(GROUND_POSE))
    else:
        value = phi(ir, ev, groups, t, q, scale)
    return derivatives.Derived(value, q, t, q_dot, gamma=q_dot is not None)


def variations(ir: ModelIR, phi_q, q):
    """[Phi_r, Pi_bar] of every row of phi_q: Pi_bar_k = 1/2 Phi_p_k G(p_k)^T per body
    (equations.body.pi_bar, with G^T a traced step)."""
    nb = ir.n_bodies
    if not nb:
        return phi_q
    pi_bar = [0.5 * phi_q[:, 3 * nb + 4 * k:3 * nb + 4 * k + 4]
              @ G_TRANSPOSE(q[3 * nb + 4 * k:3 * nb + 4 * k + 4])[0] for k in range(nb)]
    return ca.horzcat(phi_q[:, :3 * nb], *pi_bar)


def romega_gamma(jacobian, nu, t, q, v, q_dot):
    """gamma_hat of the joint rows (derivatives.gamma_hat) over the whole model."""
    return derivatives.gamma_hat(jacobian, nu, v, q, q_dot, t)


def reactions(ir: ModelIR, ev: Evaluation, groups: list, t, q, lam, shared=None) -> tuple:
    """(force, torque) of every joint's rows on its body_j (3 x joints), torque about body_i's
    joint point: derivatives.reaction_of_blocks of the joint's rows, with ground's pose
    symbolic so that the reaction on ground comes from the same AD, then fixed; `shared`:
    grounded's output."""
    rows, ground, every = shared or grounded(ir, ev, groups, t, q)
    nb = ir.n_bodies
    forces, torques = [], []
    for joint in ir.joints:
        chosen = _rows(joint.rows)
        r_j, p_j = _pose(q, nb, ground, joint.body_j)
        frame_i = every[:, nb if joint.body_i == GROUND_INDEX else joint.body_i]
        about = frame_i[:3] + ca.reshape(frame_i[3:], 3, 3) @ constant(joint.point_i)
        phi_rows = rows[chosen]
        force, torque = REACTION(ca.jacobian(phi_rows, r_j), ca.jacobian(phi_rows, p_j),
                                 lam[chosen], r_j, p_j, about)
        forces.append(force)
        torques.append(torque)
    empty = ca.SX(3, 0)
    fixed = [ca.substitute(ca.horzcat(*parts) if parts else empty, ground, ca.DM(GROUND_POSE))
             for parts in (forces, torques)]
    return fixed[0], fixed[1]


def _pose(q, nb: int, ground, k: int) -> tuple:
    """(r, p) of body k in q (ground: its symbols), by slices."""
    if k == GROUND_INDEX:
        return ground[:3], ground[3:]
    return q[3 * k:3 * k + 3], q[3 * nb + 4 * k:3 * nb + 4 * k + 4]


def _rows(rows) -> slice | list:
    """A joint's row indices as a slice when consecutive (one cheaper SX slice)."""
    rows = list(rows)
    if rows and rows == list(range(rows[0], rows[-1] + 1)):
        return slice(rows[0], rows[-1] + 1)
    return rows
