"""The results row as one casadi.Function over a bundle's results terms (equations.functions.
results_terms) and the readings (equations.readings.columns_function): the contract's columns
of every body and joint, the energy, the constraint violation, the contact and stop columns,
then the joint states and the outputs (runtime.results.row computes the same numerically).

`row_function` is what runtime.results maps over a run's rows; `mapped_bundle` the bundle of a
compiled library's terms as its library built them (mapped over the IR), from which
backends.results_row compiles the row of a compiled bundle.
"""

from __future__ import annotations

import casadi as ca

from casmech.equations import system
from casmech.equations.evaluation import Evaluation, is_inline
from casmech.equations.functions import SystemFunctions, results_terms
from casmech.model.ir import ModelIR


def row_function(functions: SystemFunctions, readings: ca.Function, symbols=None) -> ca.Function:
    """(t, q, q_dot, q_ddot, lam) -> the results row (a column): one casadi.Function over the
    bundle's terms and `readings` (the bundle's IR's readings.columns_function), inlined when
    all terms are SX and the model has at most WHERE_INLINE["results"] bodies, else called;
    `symbols` (ca.SX or ca.MX) chooses instead."""
    bundle = results_terms(functions)
    if symbols is None:
        inline = all(f.is_a("SXFunction") for f in bundle.values()) and \
            is_inline("results", functions.n_bodies)
        symbols = ca.SX if inline else ca.MX
    n, m = functions.n_coordinates, functions.n_rows
    t, q, q_dot, q_ddot, lam = (symbols.sym("t"), symbols.sym("q", n), symbols.sym("q_dot", n),
                                symbols.sym("q_ddot", n), symbols.sym("lam", m))
    nb = functions.n_bodies
    omega, alpha = bundle["body_rates"](q, q_dot, q_ddot)
    force, torque = bundle["reactions"](t, q, q_dot, lam)
    kinetic, potential = bundle["energy"](t, q, q_dot)
    phi = bundle["phi"](t, q)
    violation = ca.mmax(ca.fabs(phi)) if phi.numel() else symbols(1, 1)
    # each body's columns (BODY_COLUMNS) as one column of a matrix, then each joint's
    per_body = ca.vertcat(ca.reshape(q[:3 * nb], 3, nb), ca.reshape(q[3 * nb:], 4, nb),
                          ca.reshape(q_dot[:3 * nb], 3, nb), omega,
                          ca.reshape(q_ddot[:3 * nb], 3, nb), alpha)
    parts = [t, ca.vec(per_body), ca.vec(ca.vertcat(force, torque))]
    parts += [kinetic + potential, violation, bundle["element_outputs"](t, q, q_dot),
              readings(t, q, q_dot, q_ddot, force, torque)]
    return ca.Function("results_row", [t, q, q_dot, q_ddot, lam],
                       [ca.densify(ca.vertcat(*parts))])


def mapped_bundle(ir: ModelIR) -> SystemFunctions:
    """The results terms of `ir` as a compiled library holds them (the builder's functions
    mapped over the IR, equations.functions.mapped_functions), in a bundle of their own."""
    shared = system.System(ir, Evaluation.of(False, None))
    names = tuple(b.name for b in ir.bodies)
    terms = {name: system.function(shared, name) for name in (*system.RESULTS, "phi")}
    return SystemFunctions(terms, names, (), tuple(ir.row_info()), ir)
