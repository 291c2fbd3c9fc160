"""The saddle-point numerics of a constrained mechanism, each one CasADi Function that the
runtime and casmech.optimal both call:

    closest_point(phi, phi_q, rows)    assembly: the point of Phi(t, q) = 0 nearest to q_ref
    saddle(M pattern, P pattern)       accelerations and multipliers:
                                       [M P^T; P -diag(w)] [v_dot; lam] = [F; gamma]
    solve_saddle(M, P, F, gamma, w)    the same as expressions (MX: the LU; SX: unrolled
                                       Cholesky factors of M and the Schur complement)

closest_point is a CasADi rootfinder on the first-order optimality (KKT) conditions of
min 1/2 |q - q_ref|^2 subject to Phi_I(t, q) = 0 over the independent rows I:

    q - q_ref + Phi_I,q^T lam = 0,   Phi_I(t, q) = 0,

so its derivative with respect to t, q_ref and the parameters is the implicit one (CasADi's
rootfinder differentiates the converged root, not the iterations). With degrees of freedom
Phi = 0 has a manifold of solutions and only this condition picks one; the least-squares Newton
of runtime.assembly lands within O(|q_ref - q|^2) of it and hands it the start. Newton on the
KKT system needs the redundant rows dropped (the matrix is singular otherwise): `rows` are the
ones equations.checks.structure keeps.

saddle solves the equations of motion's linear part by a sparse direct solve (CSparse LU:
the matrix is symmetric but indefinite). w masks rows (w_k = 1 turns row k into
lam_k = P_k v_dot - gamma_k, which is 0 for a redundant row: formulations.dae's masked DAE); w = 0
is the plain KKT system. The augmented-Lagrangian iteration of formulations.augmented is the
algorithm for singular configurations, where this matrix is singular.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.core.options import Assembly

SADDLE_SOLVER = "csparse"  # sparse LU with partial pivoting (the matrix is indefinite)
DEFAULT = Assembly()  # the rootfinder's tolerance and iterations (core.options)
# solve_saddle over SX: a Cholesky factor whose diagonal spans more than 1 / this is singular
# (its squares, the pivots, span more than 1 / machine epsilon)
RANK_TOLERANCE = float(np.sqrt(np.finfo(float).eps))


def _symbols(*functions: ca.Function):
    """SX when every function is SX (calls inline), MX otherwise (compiled externals)."""
    return ca.SX if all(f.is_a("SXFunction") for f in functions) else ca.MX


def closest_point(phi: ca.Function, phi_q: ca.Function, rows,
                  name: str = "closest_point", settings: Assembly = DEFAULT) -> ca.Function:
    """(q_guess, t, q_ref[, theta]) -> (q, lam): the root of the KKT conditions (module
    docstring) by CasADi's Newton rootfinder from (q_guess, lam = 0), to
    settings.root_tolerance in at most settings.root_iterations. phi and phi_q take (t, q)
    or (t, q, theta); theta becomes the last input then. A root not reached is returned as
    the last iterate (no exception): callers check |Phi|."""
    rows = list(rows)
    n = phi_q.size2_out(0)
    n_theta = phi.size1_in(2) if phi.n_in() > 2 else None
    sym = _symbols(phi, phi_q)
    x, t, q_ref = sym.sym("x", n + len(rows)), sym.sym("t"), sym.sym("q_ref", n)
    theta = [sym.sym("theta", n_theta)] if n_theta is not None else []
    q, lam = x[:n], x[n:]
    jacobian = phi_q(t, q, *theta)[rows, :]
    residual = ca.vertcat(q - q_ref + ca.mtimes(jacobian.T, lam), phi(t, q, *theta)[rows])
    p = ca.vertcat(t, q_ref, *theta)
    kkt = ca.Function(f"{name}_kkt", [x, p], [residual])
    root = ca.rootfinder(f"{name}_root", "newton", kkt, {
        "abstol": settings.root_tolerance, "max_iter": settings.root_iterations,
        "error_on_fail": False})
    guess, t_in, ref_in = ca.MX.sym("q_guess", n), ca.MX.sym("t"), ca.MX.sym("q_ref", n)
    theta_in = [ca.MX.sym("theta", n_theta)] if n_theta is not None else []
    solution = root(ca.vertcat(guess, ca.MX.zeros(len(rows))),
                    ca.vertcat(t_in, ref_in, *theta_in))
    return ca.Function(name, [guess, t_in, ref_in, *theta_in], [solution[:n], solution[n:]],
                       ["q_guess", "t", "q_ref", *["theta"] * len(theta_in)], ["q", "lam"])


def saddle(mass: ca.Sparsity, jacobian: ca.Sparsity) -> ca.Function:
    """(M, P, F, gamma, w) -> (v_dot, lam) solving [M P^T; P -diag(w)] [v_dot; lam] =
    [F; gamma] (module docstring), M and P with the given sparsity, by CSparse's LU
    (SADDLE_SOLVER; docs/decisions/saddle-solve.md). Called with symbols it inlines
    into a graph (casmech.optimal), with numbers it is the numeric solve (runtime). A singular
    matrix raises RuntimeError; inside a mapped or buffered call CasADi first prints the
    inputs to sys.stderr, which runtime.solver_messages.without_input_dumps holds back where
    the runtime solves by least squares instead (runtime.assembly.saddle_solution)."""
    n, m = mass.size1(), jacobian.size1()
    m_in, p_in = ca.MX.sym("M", mass), ca.MX.sym("P", jacobian)
    forces, gamma, w = ca.MX.sym("F", n), ca.MX.sym("gamma", m), ca.MX.sym("w", m)
    return ca.Function("saddle", [m_in, p_in, forces, gamma, w],
                       list(solve_saddle(m_in, p_in, forces, gamma, w)),
                       ["M", "P", "F", "gamma", "w"], ["v_dot", "lam"])


def solve_saddle(mass, jacobian, forces, gamma, w) -> tuple:
    """(v_dot, lam) of [M P^T; P -diag(w)] [v_dot; lam] = [F; gamma] as expressions: over MX
    by CSparse's LU (SADDLE_SOLVER, saddle's); over SX unrolled into the graph of what builds
    M, P, F and gamma, by the range space: M = R^T R and the Schur complement
    S = P M^-1 P^T + diag(w) = R_s^T R_s by Cholesky factorizations (casadi.chol: M and S
    are symmetric positive definite, so no pivot is needed), then

        (P M^-1 P^T + diag(w)) lam = P M^-1 F - gamma,   M v_dot = F - P^T lam.

    S is singular where P lost rank and no row is masked (M where a body has no mass): the SX
    solve then gives NaN, not an error, where a factor's smallest diagonal entry is at most
    RANK_TOLERANCE times its largest or not a number (a pivot of S at roundoff of the others:
    rank lost to the last digits, where an LU would meet a zero pivot or roundoff of one)."""
    n = mass.size1()
    if isinstance(mass, ca.MX):
        lhs = ca.blockcat([[mass, jacobian.T], [jacobian, -ca.diag(w)]])
        z = ca.solve(lhs, ca.vertcat(forces, gamma), SADDLE_SOLVER)
        return z[:n], z[n:]
    factor = ca.chol(mass)  # M = R^T R, R upper triangular
    spread = ca.solve(factor.T, jacobian.T)  # R^-T P^T
    applied = ca.solve(factor.T, forces)  # R^-T F
    schur = ca.chol(ca.mtimes(spread.T, spread) + ca.diag(w))
    lam = ca.solve(schur, ca.solve(schur.T, ca.mtimes(spread.T, applied) - gamma))
    v_dot = ca.solve(factor, applied - ca.mtimes(spread, lam))
    lost = ca.logic_or(_lost_rank(factor), _lost_rank(schur))
    return ca.if_else(lost, np.nan, v_dot), ca.if_else(lost, np.nan, lam)


def _lost_rank(factor: ca.SX) -> ca.SX:
    """Whether a Cholesky factor's smallest diagonal entry is at most RANK_TOLERANCE times its
    largest (the factored matrix singular to roundoff)."""
    diagonal = ca.diag(factor)
    return ca.mmin(diagonal) <= RANK_TOLERANCE * ca.mmax(diagonal)
