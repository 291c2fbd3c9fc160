"""The DAEs of constrained motion that IDAS integrates, each as one named casadi.Function.

The index-1 DAE (stabilization "projection": the runtime projects when the constraints drift):

    x = [q, v],  z = [v_dot, lam],  p = [t0, w (one per row of P), s (one per row of P)],
    t = t0 + tau
    ode: x' = [q_dot(q, v), v_dot]
    alg: M v_dot + P_s^T lam - F = 0,   P_s v_dot - gamma_s - w * lam = 0

P_s = diag(s) P and gamma_s = s * gamma: P's rows scaled by constants the runtime sets to the
inverse row norms at the start of each integration, so lam is in force units (the true
multipliers are s * lam) and the rows are comparable. Constants, not the norms at the current
q, keep P^T lam as sparse as P (with norms of q every entry of a row depends on every
coordinate the row does: docs/decisions/rp-row-scales.md). w masks rows: w_k = 0 keeps
row k, w_k = 1 turns it into lam_k = P_k v_dot - gamma_k, which is 0 for a row that depends on
the others (redundant joints), so the row drops out smoothly and the algebraic Jacobian
[M P^T; P -diag(w)] stays non-singular. The residual is pure SX: IDAS's Newton does the
linear algebra, its Jacobian comes from AD, and the same Function is what code generation
compiles.

The stabilized index-2 DAE of Gear, Gupta and Leimkuhler (stabilization "ggl"), which keeps the
position and velocity constraints themselves at every step instead of their second derivative:

    x = [q, v],  z = [v_dot, lam, mu],  p = [t0, w, s, s_phi (one per row of Phi)]
    ode: x' = [q_dot(q, v) + Phi_q_s^T mu, v_dot]
    alg: M v_dot + P_s^T lam - F = 0,   Phi_s(q) = 0,   P_s v - nu_s = 0

(Phi_q_s and Phi_s: every row of Phi, the r-p normalization rows too in either formulation,
scaled by s_phi; in r-p P is Phi_q, and s_phi = s; mu is 0 along the exact motion.) The
masked rows become lam_k = 0 and mu_k = 0. IDAS integrates it with the algebraic unknowns out
of its error test.

The residual is written once (formulations.dae_terms.residual) and evaluated by the builder's
switch: inline over the whole model's functions (here: over a bundle, one SX graph over an
interpreted one), or mapped as a sum of per-element kernels over the same terms
(formulations.residuals: what a library compiles for larger models).
Over a parametric bundle (every function with the trailing input d, the model data:
model.parametric) either residual takes d after its own parameters: p = [t0, w, s (, s_phi), d].
"""

from __future__ import annotations

import casadi as ca

from casmech.core.options import STABILIZATIONS as STABILIZATIONS  # the residuals built
from casmech.equations.functions import symbol_type
from casmech.formulations import dae_terms as terms
from casmech.formulations.table import BODY_FORMS
from casmech.model.parametric import data_size, with_data


def sizes(functions: dict[str, ca.Function], name: str) -> tuple[int, int, int]:
    """(n_q, n_v, rows of P) of a formulation."""
    form = BODY_FORMS[name]
    jacobian = functions[form.jacobian]
    return jacobian.size1_in(1), jacobian.size2_out(0), jacobian.size1_out(0)


def residual(functions: dict[str, ca.Function], name: str,
             stabilization: str = "projection") -> ca.Function:
    """dae_<name> (projection: the index-1 DAE) or dae_ggl_<name> (the stabilized index-2
    one): (t, x, z, p) -> (ode, alg); the bundle's own when it has one (a compiled bundle
    carries them, with their Jacobians), else over the bundle's functions."""
    key = f"dae_{name}" if stabilization == "projection" else f"dae_ggl_{name}"
    if key in functions:
        return functions[key]
    return _over(functions, name, stabilization, key)


def parameters(functions: dict[str, ca.Function], name: str, stabilization: str) -> int:
    """Size of p: t0, then w and s per row of P, then s_phi per row of Phi for ggl."""
    m = sizes(functions, name)[2]
    return 1 + 2 * m + (functions["phi"].size1_out(0) if stabilization == "ggl" else 0)


def multipliers(functions: dict[str, ca.Function], name: str, stabilization: str) -> int:
    """Algebraic unknowns after v_dot: lam, and mu (one per row of Phi) for ggl."""
    m = sizes(functions, name)[2]
    return m if stabilization == "projection" else m + functions["phi"].size1_out(0)


def _column(p, start: int, stop: int):
    """p[start:stop] as a column, also when empty (a slice of a 1 x 1 p is 1 x 0)."""
    return ca.reshape(p[start:stop], stop - start, 1)


def _over(functions: dict[str, ca.Function], name: str, kind: str, key: str) -> ca.Function:
    """The residual over a bundle's functions (module docstring): SX over an SX bundle, with
    its common subexpressions merged (and so its Jacobian by AD:
    docs/decisions/codegen-small-dae-unrolled.md); MX over compiled ones."""
    form = BODY_FORMS[name]
    n_q, n_v, m = sizes(functions, name)
    n_phi = functions["phi"].size1_out(0)
    ggl = kind == "ggl"
    sym = symbol_type(functions)
    n_p = parameters(functions, name, kind)
    tau, x, z, p = (sym.sym("t"), sym.sym("x", n_q + n_v),
                    sym.sym("z", n_v + m + (n_phi if ggl else 0)),
                    sym.sym("p", n_p + data_size(functions)))
    functions = with_data(functions, p[n_p:])
    t, q, v = p[0] + tau, x[:n_q], x[n_q:]
    w, s = _column(p, 1, 1 + m), _column(p, 1 + m, 1 + 2 * m)
    v_dot, lam = z[:n_v], z[n_v:n_v + m]
    jacobian = terms.scaled(functions[form.jacobian](t, q), s)
    if ggl:
        s_phi, mu = _column(p, 1 + 2 * m, n_p), z[n_v + m:]
        # r-p: P is Phi_q (one evaluation; s_phi = s)
        phi_q = jacobian if form.jacobian == "phi_q" else \
            terms.scaled(functions["phi_q"](t, q), s_phi)
        rows = terms.Rows(jacobian, lam, w, nu_s=functions[form.nu](t, q) * s,
                          phi_s=functions["phi"](t, q) * s_phi, phi_q_s=phi_q,
                          w_phi=ca.vertcat(w, sym(n_phi - m, 1)),  # r-omega: + normalization
                          mu=mu)
    else:
        rows = terms.Rows(jacobian, lam, w, gamma_s=functions[form.gamma](t, q, v) * s)
    q_dot = v if form.q_dot is None else functions[form.q_dot](q, v)
    ode_q, ode_v, alg_v, alg_rows = terms.residual(terms.Parts(
        v, q_dot, v_dot, functions[form.mass](q), functions[form.forces](t, q, v), rows), kind)
    return ca.Function(key, [tau, x, z, p], [ca.vertcat(ode_q, ode_v), ca.vertcat(alg_v, alg_rows)],
                       ["t", "x", "z", "p"], ["ode", "alg"],
                       {"cse": True} if sym is ca.SX else {})


def problem(function: ca.Function) -> dict | ca.Function:
    """The residual Function as casadi.integrator's DAE dictionary (t, x, z, p, ode, alg); a
    function that already has the integrator's signature (t, x, z, p, u) -> (ode, alg, quad,
    zero) as it is (a compiled DAE: IDAS takes daeF and jacF from its library)."""
    if function.name_in() == ca.dyn_in():
        return function
    sym = ca.SX if function.is_a("SXFunction") else ca.MX
    args = {name: sym.sym(name, function.sparsity_in(name)) for name in function.name_in()}
    return args | function.call(args)
