"""Accelerations of a constrained mechanism by the mass-orthogonal augmented Lagrangian.

For either formulation (r-p: v = q_dot; r-omega: v = [r_dot; omega_bar]) the equations of motion
are M v_dot + P^T lam = F, P v_dot = gamma. Their augmented-Lagrangian solution (Bayo & Ledesma,
Nonlinear Dyn. 9, 1996) iterates, from lam_0 = 0,
    (M + a P^T P) v_dot_k = F - P^T lam_k-1 + a P^T gamma,
    lam_k = lam_k-1 + a (P v_dot_k - gamma).
Every iterate satisfies M v_dot_k + P^T lam_k = F exactly, and the acceleration constraint error
contracts by 1 / (1 + a s^2) per iteration for each constraint mode of mass-weighted singular
value s. M + a P^T P stays positive definite where P loses rank (singular configurations such as
the IFToMM A02 N-four-bar passing its flat poses, redundant joints), where the [M P^T; P 0] form
of an index-1 DAE is singular. There lam is the minimum-norm multiplier (every update lies in
range(P)), which spreads the reaction over redundant joints instead of choosing rows.

Each iterate is computed as a correction, v_dot_k = v_dot_k-1 + (M + a P^T P)^-1 (F - M v_dot_k-1
- P^T lam_k-1 - a P^T (P v_dot_k-1 - gamma)): the same iterates, but the solve's roundoff
(condition ~ the penalty ratio) then scales the shrinking residual, not F + a P^T gamma. Solved
directly, v_dot was 4e-8 off the saddle-point solution on tests/integration/runtime's chain; as
corrections, 1e-16 (tests/unit/formulations/test_augmented.py).

The penalty a is an input: the runtime scales it to the model (core.options.Fallback.penalty
times mass over constraint-gradient size), so no user constant is involved; the iteration
counts are the Fallback options' (fixed in the Function built). `projection` takes the same
a-damped, mass-orthogonal steps back onto the position and velocity constraints: the one
projection of casmech (runtime.projected_rk4 takes one after every Runge-Kutta step,
runtime.assembly.project calls it until |Phi| is at its tolerance).

These are kept beside numerics.kkt.saddle (the direct solve of [M P^T; P 0]) because they stay
well-posed where P loses rank, where that matrix is singular.
"""

from __future__ import annotations

import casadi as ca

from casmech.core.options import Fallback
from casmech.formulations.table import BODY_FORMS

ROW_SCALING = True  # rows of P scaled to unit length (the penalty is then relative to them)
LINEAR_SOLVER = "ldl"  # M + a P^T P is symmetric positive definite
DEFAULT = Fallback()  # the defaults (core.options)


def accelerations(functions: dict[str, ca.Function], name: str,
                  settings: Fallback = DEFAULT) -> ca.Function:
    """(t, q, v, penalty) -> (v_dot, lam), as an MX graph with sparse LDL solves
    (settings.iterations iterations)."""
    form = BODY_FORMS[name]
    mass = functions[form.mass]
    t, q = ca.MX.sym("t"), ca.MX.sym("q", mass.size1_in(0))
    v, penalty = ca.MX.sym("v", mass.size1_out(0)), ca.MX.sym("penalty")
    m, p = mass(q), functions[form.jacobian](t, q)
    f, gamma = functions[form.forces](t, q, v), functions[form.gamma](t, q, v)
    if ROW_SCALING:
        scale = 1 / ca.fmax(ca.sqrt(ca.sum2(p * p)), 1e-12)
        p, gamma = p * ca.repmat(scale, 1, p.size2()), gamma * scale
    lhs = m + penalty * p.T @ p
    lam, v_dot = ca.MX.zeros(p.size1()), ca.MX.zeros(v.size1())
    for _ in range(settings.iterations):
        residual = f - m @ v_dot - p.T @ lam - penalty * p.T @ (p @ v_dot - gamma)
        v_dot = v_dot + ca.solve(lhs, residual, LINEAR_SOLVER)
        lam = lam + penalty * (p @ v_dot - gamma)
    if ROW_SCALING:
        lam = lam * scale
    return ca.Function(f"{name}_accelerations", [t, q, v, penalty], [v_dot, lam],
                       ["t", "q", "v", "penalty"], ["v_dot", "lam"])


def projection(functions: dict[str, ca.Function], name: str,
               settings: Fallback = DEFAULT) -> ca.Function:
    """(t, q, v, penalty) -> (q, v) moved back onto Phi = 0 and then onto P v = nu, by
    mass-orthogonal steps (M / a + P^T P) dx = -P^T r (positions in r-p coordinates,
    velocities in the formulation's), as a sparse MX graph. A fixed number of Gauss-Newton
    steps for the positions (settings.projection_iterations; two take a Runge-Kutta step's
    drift on A02 N = 2, at most 4.7e-12 over its first second with 2.5 ms steps, to 4.7e-16);
    the caller checks |Phi| at the outputs all the same.
    Near a singular configuration the a-damping keeps a step from jumping along the nearly
    lost direction, i.e. onto another branch."""
    form = BODY_FORMS[name]
    mass, jacobian = functions["mass_matrix"], functions["phi_q"]
    t, q = ca.MX.sym("t"), ca.MX.sym("q", mass.size1_in(0))
    v, penalty = ca.MX.sym("v", functions[form.mass].size1_out(0)), ca.MX.sym("penalty")
    q_new, m = q, mass(q) / penalty
    for _ in range(settings.projection_iterations):
        p = jacobian(t, q_new)
        q_new = q_new - ca.solve(m + p.T @ p, p.T @ functions["phi"](t, q_new), LINEAR_SOLVER)
    p = functions[form.jacobian](t, q_new)
    residual = p @ v - functions[form.nu](t, q_new)
    lhs = functions[form.mass](q_new) / penalty + p.T @ p
    v_new = v - ca.solve(lhs, p.T @ residual, LINEAR_SOLVER)
    return ca.Function(f"{name}_projection", [t, q, v, penalty], [q_new, v_new],
                       ["t", "q", "v", "penalty"], ["q_projected", "v_projected"])
