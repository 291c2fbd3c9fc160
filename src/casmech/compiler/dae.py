"""The DAEs of constrained motion that IDAS integrates, each as one named casadi.Function.

The index-1 DAE (stabilization "projection": the runtime projects when the constraints drift):

    x = [q, v],  z = [v_dot, lam],  p = [t0, w (one per row of P)],  t = t0 + tau
    ode: x' = [q_dot(q, v), v_dot]
    alg: M v_dot + P^T lam - F = 0,   P v_dot - gamma - w * lam = 0

(P and gamma with unit-norm rows, so lam is in force units and the rows are comparable.)
w masks rows: w_k = 0 keeps row k, w_k = 1 turns it into lam_k = P_k v_dot - gamma_k, which is
0 for a row that depends on the others (redundant joints), so the row drops out smoothly and the
algebraic Jacobian [M P^T; P -diag(w)] stays non-singular. The residual is pure SX: IDAS's
Newton does the linear algebra, its Jacobian comes from AD, and the same Function is what code
generation compiles.

The stabilized index-2 DAE of Gear, Gupta and Leimkuhler (stabilization "ggl"), which keeps the
position and velocity constraints themselves at every step instead of their second derivative:

    x = [q, v],  z = [v_dot, lam, mu],  p as above
    ode: x' = [q_dot(q, v) + Phi_q^T mu, v_dot]
    alg: M v_dot + P^T lam - F = 0,   Phi(q) = 0,   P v - nu = 0

(Phi_q and Phi with the unit rows of Phi_q: every row of Phi, the r-p normalization rows too in
either formulation; mu is 0 along the exact motion.) The masked rows become lam_k = 0 and
mu_k = 0. IDAS integrates it with the algebraic unknowns out of its error test.
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


STABILIZATIONS = ("ggl", "projection")


def residual(functions: dict[str, ca.Function], name: str,
             stabilization: str = "projection") -> ca.Function:
    """dae_<name> (projection: the index-1 DAE) or dae_ggl_<name> (the stabilized index-2
    one): (t, x, z, p) -> (ode, alg); the bundle's own when it has one (a compiled bundle
    carries them, with their Jacobians)."""
    key = f"dae_{name}" if stabilization == "projection" else f"dae_ggl_{name}"
    if key in functions:
        return functions[key]
    build = _index1 if stabilization == "projection" else _ggl
    return build(functions, name, key)


def _index1(functions: dict[str, ca.Function], name: str, key: str) -> ca.Function:
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
    return ca.Function(key, [tau, x, z, p], [ca.vertcat(q_dot, v_dot), alg],
                       ["t", "x", "z", "p"], ["ode", "alg"])


def residuals(functions: dict[str, ca.Function]) -> dict[str, ca.Function]:
    """Every residual by name, both stabilizations of both formulations, over a bundle."""
    built = (residual(functions, name, kind) for name in FORMULATIONS for kind in STABILIZATIONS)
    return {function.name(): function for function in built}


def multipliers(functions: dict[str, ca.Function], name: str, stabilization: str) -> int:
    """Algebraic unknowns after v_dot: lam, and mu (one per row of Phi) for ggl."""
    m = sizes(functions, name)[2]
    return m if stabilization == "projection" else m + functions["phi"].size1_out(0)


def _ggl(functions: dict[str, ca.Function], name: str, key: str) -> ca.Function:
    form = FORMULATIONS[name]
    n_q, n_v, m = sizes(functions, name)
    n_phi = functions["phi"].size1_out(0)
    sym = _symbols(functions)
    tau, x, z, p = (sym.sym("t"), sym.sym("x", n_q + n_v), sym.sym("z", n_v + m + n_phi),
                    sym.sym("p", 1 + m))
    t, q, v, w = p[0] + tau, x[:n_q], x[n_q:], p[1:1 + m, 0]
    v_dot, lam, mu = z[:n_v], z[n_v:n_v + m], z[n_v + m:]
    raw = functions[form.jacobian](t, q)
    scale = 1 / ca.sqrt(ca.sum2(raw * raw))
    jacobian, nu = raw * ca.repmat(scale, 1, raw.size2()), functions[form.nu](t, q) * scale
    if form.jacobian == "phi_q":  # r-p: P is Phi_q (one evaluation, one scaling)
        phi_q, phi = jacobian, functions["phi"](t, q) * scale
    else:
        phi_q, phi = unit_rows(functions["phi_q"](t, q), functions["phi"](t, q))
    w_phi = ca.vertcat(w, sym(n_phi - m, 1))  # r-omega: + normalization rows (structural 0)
    alg = ca.vertcat(
        functions[form.mass](q) @ v_dot + jacobian.T @ lam - functions[form.forces](t, q, v),
        (1 - w_phi) * phi - w_phi * mu,
        (1 - w) * (jacobian @ v - nu) - w * lam)
    q_dot = v if form.q_dot is None else functions[form.q_dot](q, v)
    return ca.Function(key, [tau, x, z, p], [ca.vertcat(q_dot + phi_q.T @ mu, v_dot), alg],
                       ["t", "x", "z", "p"], ["ode", "alg"])


def problem(function: ca.Function) -> dict | ca.Function:
    """The residual Function as casadi.integrator's DAE dictionary (t, x, z, p, ode, alg); a
    function that already has the integrator's signature (t, x, z, p, u) -> (ode, alg, quad,
    zero) as it is (a compiled DAE: IDAS takes daeF and jacF from its library)."""
    if function.name_in() == ca.dyn_in():
        return function
    sym = ca.SX if function.is_a("SXFunction") else ca.MX
    args = {name: sym.sym(name, function.sparsity_in(name)) for name in function.name_in()}
    return args | function.call(args)
