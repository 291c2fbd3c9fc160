"""The bodies' quantities of a model over the per-body kernels (equations.body_kernels),
evaluated by an Evaluation: the r-p mass matrix and quadratic-velocity force, gravity, kinetic
and gravity energy, body rates, the r-omega mass matrix, kinematic map and torques, each
defined here once.

q = [r (3 nb); p (4 nb)] and v = [r_dot (3 nb); omega_bar (3 nb)] keep each quantity of all
bodies contiguous, so a body's r, p, r_dot or omega_bar is a column of a reshape (no gather).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.core.values import constant
from casmech.equations import body_kernels, evaluation
from casmech.equations.evaluation import Evaluation
from casmech.equations.rows import scatter
from casmech.model.ir import ModelIR


def columns(vector, size: int, nb: int, start: int = 0):
    """The (size x nb) matrix of a per-body block of `vector` starting at `start`."""
    return ca.reshape(vector[start:start + size * nb], size, nb)


def _call(ir: ModelIR, ev: Evaluation, name: str, *args) -> list:
    return ev.call(body_kernels.kernels(ir)[name], ir.n_bodies, *args)


def _gravity_input(ir: ModelIR, ev: Evaluation) -> list:
    """The energy kernel's gravity argument when gravity is model data."""
    return [] if body_kernels.gravity_constant(ir) is not None else [
        ev.constant(ca.vertcat(*evaluation.entries(ir.gravity)))]


def mass_matrix(ir: ModelIR, ev: Evaluation, q):
    """blkdiag(m_k I_3 ..., 4 G_k^T J_bar_k G_k ...) (7 nb x 7 nb)."""
    nb = ir.n_bodies
    blocks = _call(ir, ev, "mass", columns(q, 4, nb, 3 * nb), body_kernels.inertias(ir, ev))[0]
    diagonal = _repeated_masses(ir, ev)
    triplets = [(i, i, i) for i in range(3 * nb)]
    triplets += [(3 * nb + 4 * k + a, 3 * nb + 4 * k + b, 3 * nb + 16 * k + 4 * b + a)
                 for k in range(nb) for b in range(4) for a in range(4)]
    return scatter(7 * nb, 7 * nb, triplets, ca.vertcat(diagonal, ca.vec(blocks)), ev.sym)


def _repeated_masses(ir: ModelIR, ev: Evaluation):
    """[m_1, m_1, m_1, m_2, ...]: the translational diagonal."""
    values = [b.mass for b in ir.bodies for _ in range(3)]
    if evaluation.numeric(values):
        return ca.DM(np.array([float(ca.DM(v)) if isinstance(v, ca.SX) else v for v in values]))
    return ev.constant(ca.vertcat(*values))


def _sparse_constant(ev: Evaluation, matrix):
    """A constant matrix of the model data without its zero entries."""
    if isinstance(matrix, ca.SX) and not matrix.is_constant():
        return ev.constant(ca.sparsify(matrix))
    return ev.sym(ca.sparsify(ca.evalf(matrix) if isinstance(matrix, ca.SX) else matrix))


def romega_mass(ir: ModelIR, ev: Evaluation):
    """blkdiag(m_k I_3 ..., J_bar_k ...) (6 nb x 6 nb, v layout): a constant; mapped without its
    zero entries, inline with every entry of each J_bar (the pattern the integrators have
    always seen)."""
    blocks = [b.mass * ca.DM.eye(3) for b in ir.bodies] + [constant(b.inertia) for b in ir.bodies]
    matrix = ca.diagcat(*blocks) if blocks else ca.DM(0, 0)
    return ca.SX(matrix) if ev.inline else _sparse_constant(ev, matrix)


def quadratic_velocity(ir: ModelIR, ev: Evaluation, q, q_dot):
    """[0; 8 G_dot^T J_bar G_dot p ...] (G_dot = G(p_dot))."""
    nb = ir.n_bodies
    terms = _call(ir, ev, "quadratic", columns(q, 4, nb, 3 * nb), columns(q_dot, 4, nb, 3 * nb),
                  body_kernels.inertias(ir, ev))[0]
    return ca.vertcat(ca.DM.zeros(3 * nb), ca.vec(terms))


def gravity(ir: ModelIR, ev: Evaluation):
    """[m_k g ...; 0 (4 nb)]: the generalized force of gravity, its zero entries structurally
    zero."""
    vector = ca.vertcat(*[b.mass * constant(ir.gravity) for b in ir.bodies],
                        ca.DM.zeros(4 * ir.n_bodies)) if ir.bodies else ca.DM(0, 1)
    return _sparse_constant(ev, vector) if isinstance(vector, ca.SX) else \
        ca.sparsify(ca.evalf(vector))


def energy(ir: ModelIR, ev: Evaluation, q, q_dot) -> tuple:
    """(kinetic, gravity potential) summed over the bodies."""
    nb = ir.n_bodies
    kinetic, potential = _call(ir, ev, "energy", columns(q, 3, nb), columns(q, 4, nb, 3 * nb),
                               columns(q_dot, 3, nb), columns(q_dot, 4, nb, 3 * nb),
                               body_kernels.masses(ir, ev), body_kernels.inertias(ir, ev),
                               *_gravity_input(ir, ev))
    return ca.sum2(kinetic), ca.sum2(potential)


def body_rates(ir: ModelIR, ev: Evaluation, q, q_dot, q_ddot) -> tuple:
    """(omega, alpha): every body's global angular velocity and acceleration (3 x nb)."""
    nb = ir.n_bodies
    return tuple(_call(ir, ev, "rates", columns(q, 4, nb, 3 * nb), columns(q_dot, 4, nb, 3 * nb),
                       columns(q_ddot, 4, nb, 3 * nb)))


def romega_q_dot(ir: ModelIR, ev: Evaluation, q, v):
    """[r_dot; 1/2 G(p_k)^T omega_bar_k ...]: q_dot(q, v)."""
    nb = ir.n_bodies
    p_dot = _call(ir, ev, "q_dot", columns(q, 4, nb, 3 * nb), columns(v, 3, nb, 3 * nb))[0]
    return ca.vertcat(v[:3 * nb], ca.vec(p_dot))


def romega_q_ddot(ir: ModelIR, ev: Evaluation, q, v, v_dot):
    """The time derivative of q_dot(q, v)."""
    nb = ir.n_bodies
    p_ddot = _call(ir, ev, "q_ddot", columns(q, 4, nb, 3 * nb), columns(v, 3, nb, 3 * nb),
                   columns(v_dot, 3, nb, 3 * nb))[0]
    return ca.vertcat(v_dot[:3 * nb], ca.vec(p_ddot))


def romega_torques(ir: ModelIR, ev: Evaluation, q, v, applied):
    """n_bar - omega_bar~ J_bar omega_bar per body, n_bar = 1/2 G Q_p. Bodies whose Q_p is
    structurally zero (no force element turns them) use a kernel without it: no term that is
    always zero."""
    nb = ir.n_bodies
    applied_p = applied[3 * nb:]
    loaded = [k for k in range(nb) if any(applied_p.sparsity().has_nz(4 * k + a, 0)
                                          for a in range(4))]
    free = [k for k in range(nb) if k not in set(loaded)]
    p, w = columns(q, 4, nb, 3 * nb), columns(v, 3, nb, 3 * nb)
    j_all = body_kernels.inertias(ir, ev)
    parts = []
    for chosen, name in ((loaded, "torque"), (free, "gyroscopic")):
        if not chosen:
            continue
        inputs = [p[:, chosen]] + ([ca.reshape(applied_p, 4, nb)[:, chosen]]
                                   if name == "torque" else []) + [w[:, chosen], j_all[:, chosen]]
        parts.append(ev.call(body_kernels.kernels(ir)[name], len(chosen), *inputs)[0])
    order = [3 * k + a for k in loaded + free for a in range(3)]
    stacked = ca.vec(ca.horzcat(*parts)) if parts else ev.sym(0, 1)
    inverse = [int(k) for k in np.argsort(order)]
    return stacked[inverse]
