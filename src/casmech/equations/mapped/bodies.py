"""Per-body functions (mass matrices, quadratic-velocity terms, kinetic and gravity energy, body
rates, the r-omega kinematic map and torques) as one SX kernel per quantity, mapped over the
bodies with their masses and inertias as data: code whose size does not grow with the number
of bodies. Each kernel wraps the term of ONE body that equations.eom / equations.romega sum over
the bodies (equations.body); tests/codegen/test_mapped.py checks the mapped functions against
the unrolled ones.

q = [r (3 nb); p (4 nb)] and v = [r_dot (3 nb); omega_bar (3 nb)] keep each quantity of all
bodies contiguous, so a body's r, p, r_dot or omega_bar is a column of a reshape (no gather).
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from casmech.equations import body, eom, romega
from casmech.equations.mapped.kernels import mapped, scatter
from casmech.model.ir import ModelIR


def columns(vector, size: int, nb: int, start: int = 0):
    """The (size x nb) matrix of a per-body block of `vector` starting at `start`."""
    return ca.reshape(vector[start:start + size * nb], size, nb)


def inertia_pattern(ir: ModelIR) -> tuple[bool, ...]:
    """Entries of J_bar non-zero in some body: the kernels' inertia input has this sparsity, so
    a zero that simplifies the unrolled expressions (diagonal inertias) simplifies them too."""
    return tuple(bool(any(b.inertia.ravel(order="F")[k] != 0 for b in ir.bodies))
                 for k in range(9))


def inertias(ir: ModelIR) -> ca.DM:
    pattern = inertia_pattern(ir)
    chosen = [k for k in range(9) if pattern[k]]
    values = np.concatenate([np.asarray(b.inertia, float).ravel(order="F")[chosen]
                             for b in ir.bodies])
    return ca.DM(ca.repmat(inertia_sparsity(pattern), 1, ir.n_bodies), values)


def inertia_sparsity(pattern) -> ca.Sparsity:
    """The (9 x 1) sparsity of J_bar's entries (column-major) that `pattern` marks non-zero."""
    nonzero = [k for k, on in enumerate(pattern) if on]
    return ca.Sparsity.triplet(len(pattern), 1, nonzero, [0] * len(nonzero))


def masses(ir: ModelIR) -> ca.DM:
    return ca.DM(np.array([[b.mass for b in ir.bodies]]))


def kernels(ir: ModelIR) -> dict[str, ca.Function]:
    return _kernels(inertia_pattern(ir), tuple(float(g) for g in ir.gravity))


@lru_cache(maxsize=16)
def _kernels(pattern: tuple[bool, ...], gravity_vector: tuple[float, ...]
             ) -> dict[str, ca.Function]:
    """The per-body kernels (equations.body's terms) for inertias with this sparsity and this
    gravity (a constant)."""
    p, p_dot, p_ddot = ca.SX.sym("p", 4), ca.SX.sym("p_dot", 4), ca.SX.sym("p_ddot", 4)
    r, r_dot, gravity = ca.SX.sym("r", 3), ca.SX.sym("r_dot", 3), ca.DM(gravity_vector)
    w, w_dot, q_p = ca.SX.sym("w", 3), ca.SX.sym("w_dot", 3), ca.SX.sym("q_p", 4)
    m, j_flat = ca.SX.sym("m"), ca.SX.sym("J", inertia_sparsity(pattern))
    inertia = ca.reshape(ca.densify(j_flat), 3, 3)
    p_dot_of = body.p_dot(p, w)
    return {
        "mass": ca.Function("body_mass", [p, j_flat], [body.mass_block(p, inertia)]),
        "quadratic": ca.Function("body_quadratic", [p, p_dot, j_flat],
                                 [body.quadratic_velocity(p, p_dot, inertia)]),
        "energy": ca.Function("body_energy", [r, p, r_dot, p_dot, m, j_flat], [
            body.kinetic_energy(m, inertia, r_dot, p, p_dot),
            body.gravity_potential(m, gravity, r)]),
        "rates": ca.Function("body_rates", [p, p_dot, p_ddot],
                             body.global_rates(p, p_dot, p_ddot)),
        "q_dot": ca.Function("body_p_dot", [p, w], [p_dot_of]),
        "q_ddot": ca.Function("body_p_ddot", [p, w, w_dot],
                              [romega.q_ddot(p_dot_of, p, w, w_dot)]),
        "torque": ca.Function("body_torque", [p, q_p, w, j_flat],
                              [romega.body_torque(p, q_p, w, inertia)]),
        "gyroscopic": ca.Function("body_gyroscopic", [p, w, j_flat],
                                  [romega.body_torque(p, ca.SX(4, 1), w, inertia)]),
    }


def _map(ir: ModelIR, name: str, *args):
    return mapped(kernels(ir)[name], ir.n_bodies)(*args)


def mass_matrix(ir: ModelIR, q):
    """blkdiag(m_k I_3 ..., 4 G_k^T J_bar_k G_k ...) (equations.eom.mass_matrix)."""
    nb = ir.n_bodies
    blocks = _map(ir, "mass", columns(q, 4, nb, 3 * nb), inertias(ir))
    diagonal = ca.DM(np.repeat([b.mass for b in ir.bodies], 3))
    triplets = [(i, i, i) for i in range(3 * nb)]
    triplets += [(3 * nb + 4 * k + a, 3 * nb + 4 * k + b, 3 * nb + 16 * k + 4 * b + a)
                 for k in range(nb) for b in range(4) for a in range(4)]
    return scatter(7 * nb, 7 * nb, triplets, ca.vertcat(diagonal, ca.vec(blocks)))


def romega_mass(ir: ModelIR):
    """blkdiag(m_k I_3 ..., J_bar_k ...) (equations.romega.mass): a constant. Its zero entries
    are left out of the pattern (the unrolled function lists them), so that the DAE's Jacobian
    has the unrolled sparsity: there they vanish when M v_dot is formed."""
    return ca.MX(ca.sparsify(ca.evalf(romega.mass(ir))))


def quadratic_velocity(ir: ModelIR, q, q_dot):
    """[0; 8 G_dot^T J_bar G_dot p ...] (equations.eom.quadratic_velocity)."""
    nb = ir.n_bodies
    terms = _map(ir, "quadratic", columns(q, 4, nb, 3 * nb), columns(q_dot, 4, nb, 3 * nb),
                 inertias(ir))
    return ca.vertcat(ca.DM.zeros(3 * nb), ca.vec(terms))


def gravity(ir: ModelIR) -> ca.DM:
    """equations.eom.gravity, its zero entries structurally zero (as they vanish from the
    unrolled expressions)."""
    return ca.sparsify(ca.evalf(eom.gravity(ir)))


def energy(ir: ModelIR, q, q_dot) -> tuple:
    """(kinetic, gravity potential) summed over the bodies."""
    nb = ir.n_bodies
    kinetic, potential = _map(ir, "energy", columns(q, 3, nb), columns(q, 4, nb, 3 * nb),
                              columns(q_dot, 3, nb), columns(q_dot, 4, nb, 3 * nb), masses(ir),
                              inertias(ir))
    return ca.sum2(kinetic), ca.sum2(potential)


def body_rates(ir: ModelIR, q, q_dot, q_ddot) -> tuple:
    nb = ir.n_bodies
    return _map(ir, "rates", columns(q, 4, nb, 3 * nb), columns(q_dot, 4, nb, 3 * nb),
                columns(q_ddot, 4, nb, 3 * nb))


def romega_q_dot(ir: ModelIR, q, v):
    """[r_dot; 1/2 G(p_k)^T omega_bar_k ...] (equations.romega.q_dot_of)."""
    nb = ir.n_bodies
    p_dot = _map(ir, "q_dot", columns(q, 4, nb, 3 * nb), columns(v, 3, nb, 3 * nb))
    return ca.vertcat(v[:3 * nb], ca.vec(p_dot))


def romega_q_ddot(ir: ModelIR, q, v, v_dot):
    nb = ir.n_bodies
    p_ddot = _map(ir, "q_ddot", columns(q, 4, nb, 3 * nb), columns(v, 3, nb, 3 * nb),
                  columns(v_dot, 3, nb, 3 * nb))
    return ca.vertcat(v_dot[:3 * nb], ca.vec(p_ddot))


def romega_torques(ir: ModelIR, q, v, applied):
    """n_bar - omega_bar~ J_bar omega_bar per body, n_bar = 1/2 G Q_p (equations.romega.forces).
    Bodies whose Q_p is structurally zero (no force element turns them) use a kernel without
    it, as the unrolled expression loses the term: the same sparsity."""
    nb = ir.n_bodies
    applied_p = applied[3 * nb:]
    loaded = [k for k in range(nb) if any(applied_p.sparsity().has_nz(4 * k + a, 0)
                                          for a in range(4))]
    free = [k for k in range(nb) if k not in set(loaded)]
    p, w = columns(q, 4, nb, 3 * nb), columns(v, 3, nb, 3 * nb)
    j_all = inertias(ir)
    parts = []
    for bodies, name in ((loaded, "torque"), (free, "gyroscopic")):
        if not bodies:
            continue
        inputs = [p[:, bodies]] + ([ca.reshape(applied_p, 4, nb)[:, bodies]]
                                   if name == "torque" else []) + [w[:, bodies], j_all[:, bodies]]
        parts.append(mapped(kernels(ir)[name], len(bodies))(*inputs))
    order = [3 * k + a for k in loaded + free for a in range(3)]
    stacked = ca.vec(ca.horzcat(*parts)) if parts else ca.MX(0, 1)
    inverse = [int(k) for k in np.argsort(order)]
    return stacked[inverse]
