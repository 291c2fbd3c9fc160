"""The index-1 DAE of constrained motion that IDAS integrates, as one named casadi.Function.

    x = [q, v],  z = [v_dot, lam],  p = [t0, w (one per row of P)],  t = t0 + tau
    ode: x' = [q_dot(q, v), v_dot]
    alg: M v_dot + P^T lam - F = 0,   P v_dot - gamma - w * lam = 0

(P and gamma with unit-norm rows, so lam is in force units and the rows are comparable.)
w masks rows: w_k = 0 keeps row k, w_k = 1 turns it into lam_k = P_k v_dot - gamma_k, which is
0 for a row that depends on the others (redundant joints), so the row drops out smoothly and the
algebraic Jacobian [M P^T; P -diag(w)] stays non-singular. The residual is pure SX: IDAS's
Newton does the linear algebra, its Jacobian comes from AD, and the same Function is what code
generation compiles.
"""

from __future__ import annotations

import casadi as ca

from casmech.compiler.formulations import FORMULATIONS


def _symbols(functions: dict[str, ca.Function]):
    """SX symbols when every function is SX (calls inline), MX otherwise (compiled externals)."""
    return ca.SX if all(f.is_a("SXFunction") for f in functions.values()) else ca.MX


def sizes(functions: dict[str, ca.Function], name: str) -> tuple[int, int, int]:
    """(n_q, n_v, rows of P) of a formulation."""
    form = FORMULATIONS[name]
    jacobian = functions[form.jacobian]
    return jacobian.size1_in(1), jacobian.size2_out(0), jacobian.size1_out(0)


def unit_rows(jacobian, gamma):
    """P and gamma with every row of P scaled to unit norm (rows never vanish for a joint)."""
    scale = 1 / ca.sqrt(ca.sum2(jacobian * jacobian))
    return jacobian * ca.repmat(scale, 1, jacobian.size2()), gamma * scale


def residual(functions: dict[str, ca.Function], name: str) -> ca.Function:
    """dae_<name>: (t, x, z, p) -> (ode, alg), the semi-explicit index-1 DAE above; the
    bundle's own when it has one (a compiled bundle carries it, with its Jacobian)."""
    if f"dae_{name}" in functions:
        return functions[f"dae_{name}"]
    form = FORMULATIONS[name]
    n_q, n_v, m = sizes(functions, name)
    sym = _symbols(functions)
    tau, x, z, p = sym.sym("t"), sym.sym("x", n_q + n_v), sym.sym("z", n_v + m), sym.sym("p", 1 + m)
    t, q, v, v_dot, lam, w = p[0] + tau, x[:n_q], x[n_q:], z[:n_v], z[n_v:], p[1:1 + m, 0]
    jacobian, gamma = unit_rows(functions[form.jacobian](t, q), functions[form.gamma](t, q, v))
    alg = ca.vertcat(
        functions[form.mass](q) @ v_dot + jacobian.T @ lam - functions[form.forces](t, q, v),
        jacobian @ v_dot - gamma - w * lam)
    q_dot = v if form.q_dot is None else functions[form.q_dot](q, v)
    return ca.Function(f"dae_{name}", [tau, x, z, p], [ca.vertcat(q_dot, v_dot), alg],
                       ["t", "x", "z", "p"], ["ode", "alg"])


def problem(function: ca.Function) -> dict:
    """The residual Function as casadi.integrator's DAE dictionary (t, x, z, p, ode, alg)."""
    sym = ca.SX if function.is_a("SXFunction") else ca.MX
    args = {name: sym.sym(name, function.sparsity_in(name)) for name in function.name_in()}
    return args | function.call(args)
