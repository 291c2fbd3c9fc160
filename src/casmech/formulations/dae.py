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

Over a parametric bundle (every function with the trailing input d, the model data:
model.parametric) either residual takes d after its own parameters: p = [t0, w, s (, s_phi), d].
"""

from __future__ import annotations

import casadi as ca

from casmech.equations.functions import symbol_type
from casmech.formulations.table import FORMULATIONS
from casmech.model.parametric import data_size, with_data


def sizes(functions: dict[str, ca.Function], name: str) -> tuple[int, int, int]:
    """(n_q, n_v, rows of P) of a formulation."""
    form = FORMULATIONS[name]
    jacobian = functions[form.jacobian]
    return jacobian.size1_in(1), jacobian.size2_out(0), jacobian.size1_out(0)


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


def parameters(functions: dict[str, ca.Function], name: str, stabilization: str) -> int:
    """Size of p: t0, then w and s per row of P, then s_phi per row of Phi for ggl."""
    m = sizes(functions, name)[2]
    return 1 + 2 * m + (functions["phi"].size1_out(0) if stabilization == "ggl" else 0)


def _index1(functions: dict[str, ca.Function], name: str, key: str) -> ca.Function:
    form = FORMULATIONS[name]
    n_q, n_v, m = sizes(functions, name)
    sym = symbol_type(functions)
    n_p = parameters(functions, name, "projection")
    tau, x, z, p = (sym.sym("t"), sym.sym("x", n_q + n_v), sym.sym("z", n_v + m),
                    sym.sym("p", n_p + data_size(functions)))
    functions = with_data(functions, p[n_p:])
    t, q, v, v_dot, lam = p[0] + tau, x[:n_q], x[n_q:], z[:n_v], z[n_v:]
    w, s = _column(p, 1, 1 + m), _column(p, 1 + m, 1 + 2 * m)
    jacobian = scaled(functions[form.jacobian](t, q), s)
    alg = ca.vertcat(
        dynamics(functions[form.mass](q), v_dot, jacobian, lam, functions[form.forces](t, q, v)),
        acceleration_rows(jacobian, v_dot, functions[form.gamma](t, q, v) * s, w, lam))
    q_dot = v if form.q_dot is None else functions[form.q_dot](q, v)
    return ca.Function(key, [tau, x, z, p], [ca.vertcat(q_dot, v_dot), alg],
                       ["t", "x", "z", "p"], ["ode", "alg"], _options(sym))


def _options(sym) -> dict:
    """An SX residual with its common subexpressions merged, and so its Jacobian by AD
    (docs/decisions/codegen-small-dae-unrolled.md)."""
    return {"cse": True} if sym is ca.SX else {}


def _column(p, start: int, stop: int):
    """p[start:stop] as a column, also when empty (a slice of a 1 x 1 p is 1 x 0)."""
    return ca.reshape(p[start:stop], stop - start, 1)


def scaled(matrix, s):
    """diag(s) matrix."""
    return matrix * ca.repmat(s, 1, matrix.size2())


# The residual's terms, written once for the whole system (here) and for one element
# (formulations.residual_kernels). P_s, phi_s, ...: the rows already scaled by their s (or s_phi).

def constraint_forces(p_s, lam):
    """P_s^T lam."""
    return p_s.T @ lam


def dynamics(mass, v_dot, p_s, lam, forces):
    """M v_dot + P_s^T lam - F."""
    return mass @ v_dot + constraint_forces(p_s, lam) - forces


def acceleration_rows(p_s, v_dot, gamma_s, w, lam):
    """P_s v_dot - gamma_s - w lam (projection)."""
    return p_s @ v_dot - gamma_s - w * lam


def position_rows(phi_s, w_phi, mu):
    """(1 - w) phi_s - w mu (ggl)."""
    return (1 - w_phi) * phi_s - w_phi * mu


def velocity_rows(p_s, v, nu_s, w, lam):
    """(1 - w) (P_s v - nu_s) - w lam (ggl)."""
    return (1 - w) * (p_s @ v - nu_s) - w * lam


def ggl_q_dot(q_dot, phi_q_s, mu):
    """q_dot + Phi_q_s^T mu (ggl)."""
    return q_dot + constraint_forces(phi_q_s, mu)


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
    sym = symbol_type(functions)
    n_p = parameters(functions, name, "ggl")
    tau, x, z, p = (sym.sym("t"), sym.sym("x", n_q + n_v), sym.sym("z", n_v + m + n_phi),
                    sym.sym("p", n_p + data_size(functions)))
    functions = with_data(functions, p[n_p:])
    t, q, v = p[0] + tau, x[:n_q], x[n_q:]
    w, s, s_phi = _column(p, 1, 1 + m), _column(p, 1 + m, 1 + 2 * m), _column(p, 1 + 2 * m, n_p)
    v_dot, lam, mu = z[:n_v], z[n_v:n_v + m], z[n_v + m:]
    jacobian = scaled(functions[form.jacobian](t, q), s)
    nu = functions[form.nu](t, q) * s
    # r-p: P is Phi_q (one evaluation; s_phi = s)
    phi_q = jacobian if form.jacobian == "phi_q" else scaled(functions["phi_q"](t, q), s_phi)
    phi = functions["phi"](t, q) * s_phi
    w_phi = ca.vertcat(w, sym(n_phi - m, 1))  # r-omega: + normalization rows (structural 0)
    alg = ca.vertcat(
        dynamics(functions[form.mass](q), v_dot, jacobian, lam, functions[form.forces](t, q, v)),
        position_rows(phi, w_phi, mu), velocity_rows(jacobian, v, nu, w, lam))
    q_dot = v if form.q_dot is None else functions[form.q_dot](q, v)
    return ca.Function(key, [tau, x, z, p], [ca.vertcat(ggl_q_dot(q_dot, phi_q, mu), v_dot), alg],
                       ["t", "x", "z", "p"], ["ode", "alg"], _options(sym))


def problem(function: ca.Function) -> dict | ca.Function:
    """The residual Function as casadi.integrator's DAE dictionary (t, x, z, p, ode, alg); a
    function that already has the integrator's signature (t, x, z, p, u) -> (ode, alg, quad,
    zero) as it is (a compiled DAE: IDAS takes daeF and jacF from its library)."""
    if function.name_in() == ca.dyn_in():
        return function
    sym = ca.SX if function.is_a("SXFunction") else ca.MX
    args = {name: sym.sym(name, function.sparsity_in(name)) for name in function.name_in()}
    return args | function.call(args)
