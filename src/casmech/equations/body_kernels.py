"""One SX kernel per body quantity (equations.body's terms of ONE body: the r-p mass block and
quadratic velocity, kinetic and gravity energy, body rates, the r-omega kinematic map and
torques), and the bodies' data: masses and inertias as kernel inputs, so one kernel serves
every body (inline: expanded per body; mapped: one call over all).

A kernel's inertia input has the sparsity of the entries of J_bar that are non-zero in some
body (a diagonal inertia keeps its zeros out of the graph). Gravity is a constant inside the
energy kernel, or its input when it is model data (symbolic).
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from casmech.equations import body, evaluation
from casmech.equations.evaluation import Evaluation
from casmech.model.ir import ModelIR


def inertia_pattern(ir: ModelIR) -> tuple[bool, ...]:
    """Entries of J_bar (column-major) non-zero in some body."""
    flat = [evaluation.entries(b.inertia, "F") for b in ir.bodies]
    return tuple(any(not evaluation.is_zero(entries[k]) for entries in flat) for k in range(9))


def inertias(ir: ModelIR, ev: Evaluation):
    """(pattern x nb): every body's inertia entries on inertia_pattern, as kernel data."""
    pattern = inertia_pattern(ir)
    chosen = [k for k in range(9) if pattern[k]]
    values = [[evaluation.entries(b.inertia, "F")[k] for k in chosen] for b in ir.bodies]
    return ev.constant(evaluation.columns(evaluation.sparse_column(pattern), values))


def masses(ir: ModelIR, ev: Evaluation):
    """(1 x nb) masses, as kernel data."""
    values = [[b.mass] for b in ir.bodies]
    return ev.constant(evaluation.columns(ca.Sparsity.dense(1, 1), values))


def gravity_constant(ir: ModelIR) -> tuple[float, ...] | None:
    """Gravity as numbers (baked into the energy kernel), or None when it is model data."""
    values = evaluation.entries(ir.gravity)
    return tuple(float(ca.DM(g)) if isinstance(g, ca.SX) else float(g) for g in values) \
        if evaluation.numeric(values) else None


def kernels(ir: ModelIR) -> dict[str, ca.Function]:
    return _kernels(inertia_pattern(ir), gravity_constant(ir))


def kernels_for(pattern: tuple[bool, ...]) -> dict[str, ca.Function]:
    """The kernels for inertias with this sparsity (those that do not read gravity)."""
    return _kernels(pattern, (0.0, 0.0, 0.0))


def inertia_matrix(j_flat) -> ca.SX:
    """The 3 x 3 J_bar of a kernel's inertia input."""
    return ca.reshape(ca.densify(j_flat), 3, 3)


@lru_cache(maxsize=16)
def _kernels(pattern: tuple[bool, ...], gravity_vector: tuple[float, ...] | None
             ) -> dict[str, ca.Function]:
    """The per-body kernels for inertias with this sparsity and this gravity (None: an input
    of the energy kernel, after the inertia)."""
    p, p_dot, p_ddot = ca.SX.sym("p", 4), ca.SX.sym("p_dot", 4), ca.SX.sym("p_ddot", 4)
    r, r_dot = ca.SX.sym("r", 3), ca.SX.sym("r_dot", 3)
    w, w_dot, q_p = ca.SX.sym("w", 3), ca.SX.sym("w_dot", 3), ca.SX.sym("q_p", 4)
    m, j_flat = ca.SX.sym("m"), ca.SX.sym("J", evaluation.sparse_column(pattern))
    inertia = inertia_matrix(j_flat)
    gravity = ca.SX.sym("g", 3) if gravity_vector is None else ca.DM(gravity_vector)
    p_dot_of = body.p_dot(p, w)
    return {
        "mass": ca.Function("body_mass", [p, j_flat], [body.mass_block(p, inertia)]),
        "quadratic": ca.Function("body_quadratic", [p, p_dot, j_flat],
                                 [body.quadratic_velocity(p, p_dot, inertia)]),
        "energy": ca.Function("body_energy", [r, p, r_dot, p_dot, m, j_flat] + (
            [gravity] if gravity_vector is None else []), [
            body.kinetic_energy(m, inertia, r_dot, p, p_dot),
            body.gravity_potential(m, gravity, r)]),
        "rates": ca.Function("body_rates", [p, p_dot, p_ddot],
                             body.global_rates(p, p_dot, p_ddot)),
        "q_dot": ca.Function("body_p_dot", [p, w], [p_dot_of]),
        "q_ddot": ca.Function("body_p_ddot", [p, w, w_dot],
                              [body.q_ddot(p_dot_of, p, w, w_dot)]),
        "torque": ca.Function("body_torque", [p, q_p, w, j_flat],
                              [body.romega_torque(p, q_p, w, inertia)]),
        "gyroscopic": ca.Function("body_gyroscopic", [p, w, j_flat],
                                  [body.romega_torque(p, ca.SX(4, 1), w, inertia)]),
    }
