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

Both are built once, as sums of elements (one per joint, body and force element:
formulations.residuals over the kernels of formulations.residual_kernels): inline, one SX
graph, for an interpreted bundle (its functions' source, the IR); mapped for code generation.
Over a symbolic IR (model.parametric, every function with the trailing input d) either
residual takes d after its own parameters: p = [t0, w, s (, s_phi), d].
"""

from __future__ import annotations

import casadi as ca

from casmech.formulations import residuals
from casmech.formulations.table import FORMULATIONS


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
    carries them, with their Jacobians), else built inline from the IR of an interpreted
    bundle (equations.functions.LazyFunctions.source)."""
    key = f"dae_{name}" if stabilization == "projection" else f"dae_ggl_{name}"
    if key in functions:
        return functions[key]
    source = getattr(functions, "source", None)
    if source is None:
        raise ValueError(f"{key}: the bundle has no DAE residual and no model to build it from")
    ir, data = source
    return residuals.residual(ir, name, stabilization, data)


def parameters(functions: dict[str, ca.Function], name: str, stabilization: str) -> int:
    """Size of p: t0, then w and s per row of P, then s_phi per row of Phi for ggl."""
    m = sizes(functions, name)[2]
    return 1 + 2 * m + (functions["phi"].size1_out(0) if stabilization == "ggl" else 0)


def residuals_of(functions: dict[str, ca.Function]) -> dict[str, ca.Function]:
    """Every residual by name, both stabilizations of both formulations, of a bundle."""
    built = (residual(functions, name, kind) for name in FORMULATIONS for kind in STABILIZATIONS)
    return {function.name(): function for function in built}


def multipliers(functions: dict[str, ca.Function], name: str, stabilization: str) -> int:
    """Algebraic unknowns after v_dot: lam, and mu (one per row of Phi) for ggl."""
    m = sizes(functions, name)[2]
    return m if stabilization == "projection" else m + functions["phi"].size1_out(0)


def problem(function: ca.Function) -> dict | ca.Function:
    """The residual Function as casadi.integrator's DAE dictionary (t, x, z, p, ode, alg); a
    function that already has the integrator's signature (t, x, z, p, u) -> (ode, alg, quad,
    zero) as it is (a compiled DAE: IDAS takes daeF and jacF from its library)."""
    if function.name_in() == ca.dyn_in():
        return function
    sym = ca.SX if function.is_a("SXFunction") else ca.MX
    args = {name: sym.sym(name, function.sparsity_in(name)) for name in function.name_in()}
    return args | function.call(args)
