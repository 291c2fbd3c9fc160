"""The constraint rows' derivatives in the inline evaluation: every row's phi expanded from its
kernel (equations.row_kernels.phi) into one SX graph, then differentiated as a whole by CasADi
(equations.derivatives). The mapped evaluation differentiates inside each kernel instead: the
same derivatives of the same phi (the chain rule commutes with the gather), where AD of the
whole graph shares each body's rotation derivatives between its rows. Entries that are the
constant 0 are left out of the Jacobians' patterns, as the mapped evaluation leaves them out.
"""

from __future__ import annotations

import casadi as ca

from casmech.equations import body, derivatives
from casmech.equations import row_kernels as kernels
from casmech.equations.derivatives import GROUND_POSE
from casmech.equations.evaluation import Evaluation
from casmech.equations.layout import Layout, ordered
from casmech.equations.symbols import Coordinates
from casmech.model.ir import ModelIR


def phi(ir: ModelIR, ev: Evaluation, groups: list, t, q, scale=None, ground=None):
    """phi (joint rows, then p^T p - 1 per body); ground's pose the symbols `ground` (7) or the
    constant GROUND_POSE."""
    padded = Layout(ir.n_bodies).pad_q(q, ground)
    parts, order = [], []
    for group in groups:
        kernel = kernels.phi(group.key, ground is not None)
        parts.append(group.call(kernel, group.x(padded), group.c, group.f(t, scale))[0].T)
        order += group.rows
    nb, m = ir.n_bodies, len(ir.primitives)
    if nb:
        norm = ev.call(kernels.normalization()[0], nb, Layout(nb).p(q))[0]
        parts.append(norm.T)
        order += list(range(m, m + nb))
    return ordered(parts, order, ca.SX)


def constraints(ir: ModelIR, ev: Evaluation, groups: list, t, q, q_dot=None,
                scale=None) -> dict:
    """phi, phi_q, nu and (given q_dot) gamma by AD of the whole phi."""
    value = phi(ir, ev, groups, t, q, scale)
    out = derivatives.of_phi(value, q, t, q_dot if q_dot is not None else ca.SX(q.numel(), 1))
    if q_dot is None:
        del out["gamma"]
    out["phi"] = value
    out["phi_q"] = ca.sparsify(out["phi_q"])
    return out


def variations(ir: ModelIR, phi_q, q):
    """[Phi_r, Pi_bar] of every row of phi_q: Pi_bar_k = 1/2 Phi_p_k G(p_k)^T per body."""
    nb = ir.n_bodies
    if not nb:
        return phi_q
    pi_bar = [body.pi_bar(phi_q[:, 3 * nb + 4 * k:3 * nb + 4 * k + 4],
                          q[3 * nb + 4 * k:3 * nb + 4 * k + 4]) for k in range(nb)]
    return ca.sparsify(ca.horzcat(phi_q[:, :3 * nb], *pi_bar))


def romega_gamma(jacobian, nu, t, q, v, q_dot):
    """gamma_hat of the joint rows (derivatives.gamma_hat) over the whole model."""
    return derivatives.gamma_hat(jacobian, nu, v, q, q_dot, t)


def reactions(ir: ModelIR, ev: Evaluation, groups: list, t, q, lam) -> tuple:
    """(force, torque) of every joint's rows on its body_j (3 x joints), torque about body_i's
    joint point: derivatives.reaction of the joint's rows, with ground's pose symbolic so that
    the reaction on ground comes from the same AD, then fixed."""
    ground = ca.SX.sym("q_ground", 7)
    x = Coordinates(t, q, ca.SX(q.numel(), 1), ca.SX(q.numel(), 1), ground, ir.n_bodies)
    rows = phi(ir, ev, groups, t, q, ground=ground)
    forces, torques = [], []
    for joint in ir.joints:
        chosen = _rows(joint.rows)
        force, torque = derivatives.reaction(rows[chosen], lam[chosen], x.r(joint.body_j),
                                             x.p(joint.body_j),
                                             x.point(joint.body_i, joint.point_i))
        forces.append(force)
        torques.append(torque)
    empty = ca.SX(3, 0)
    fixed = [ca.substitute(ca.horzcat(*parts) if parts else empty, ground, ca.DM(GROUND_POSE))
             for parts in (forces, torques)]
    return fixed[0], fixed[1]


def _rows(rows) -> slice | list:
    """A joint's row indices as a slice when consecutive (one cheaper SX slice)."""
    rows = list(rows)
    if rows and rows == list(range(rows[0], rows[-1] + 1)):
        return slice(rows[0], rows[-1] + 1)
    return rows
