"""Prescribed motion (kinematics, inverse dynamics) over an output grid as CasADi Functions.

One output row is one call of

    prescribed_step(s, u) -> (s_next, checks)
    s = [q; q_dot; q_ddot] at the previous output time, u = [t; h] (h = t - previous time)
    s_next = the state at t, checks = [lam; max |Phi(t, q)|; pivot ratio of Phi_q(t, q)]

positions: ITERATIONS Newton steps from the second-order predictor q + h q_dot + h^2/2 q_ddot,
each the least-squares step with the QR of Phi_q at the predictor (a chord iteration: the
predictor is within e = O(h^3) of the solution, the first step leaves O(e^2) as Newton's
would, each later one multiplies the error by O(e)); then with the QR of Phi_q at the new
positions: Phi_q q_dot = nu, Phi_q q_ddot = gamma, and the minimum-norm
Phi_q^T lam = Q - M q_ddot. Least squares and
minimum norm are what the per-row code computes with numpy.linalg.lstsq, so redundant rows
(Bricard) give the same reactions. The checks tell the runtime whether the row converged
(max |Phi| within the assembly's tolerance, core.options.Assembly) and whether Phi_q may have
lost rank (a small pivot ratio); such rows are left to the per-row code, which reports the
failure with its joints.

For a fully driven mechanism Phi_q alone fixes q_ddot, so the step solves with Phi_q's QR
rather than numerics.kkt.saddle's [M Phi_q^T; Phi_q 0] (twice the unknowns): one
factorization serves velocities, accelerations and the multipliers.

`grid(step, rows)` maps the step over a grid with mapaccum, nested (an inner map of CHUNK
rows inside an outer one), so building the mapped Function costs O(CHUNK + rows / CHUNK)
instead of O(rows); the grid is padded to a multiple of CHUNK.
"""

from __future__ import annotations

import casadi as ca

from casmech.equations.functions import symbol_type
from casmech.model.parametric import data_size, with_data
from casmech.numerics.sparse_qr import sparse_qr

ITERATIONS = 3  # chord Newton steps per row; rows that need more go to the per-row code
CHUNK = 32  # rows of the inner mapaccum


def step(functions: dict[str, ca.Function], iterations: int = ITERATIONS) -> ca.Function:
    """prescribed_step over a bundle (module docstring); the bundle's own when it has one."""
    if "prescribed_step" in functions and iterations == ITERATIONS:
        return functions["prescribed_step"]
    n = functions["phi_q"].size2_out(0)
    qr = sparse_qr(functions["phi_q"].sparsity_out(0), "phi_q_qr")
    sym = symbol_type(functions)
    s, u, d = sym.sym("s", 3 * n), sym.sym("u", 2), sym.sym("d", data_size(functions))
    called = with_data(functions, d)  # a parametric bundle's: d, a third input of the step
    phi, phi_q, nu, gamma = (called[k] for k in ("phi", "phi_q", "nu", "gamma"))
    mass, forces = called["mass_matrix"], called["generalized_forces"]
    t, h = u[0], u[1]
    q, q_dot, q_ddot = s[:n], s[n:2 * n], s[2 * n:]
    q = q + h * q_dot + 0.5 * h * h * q_ddot
    factors = qr.factor(phi_q(t, q))[:3]
    for _ in range(iterations):
        q = q - qr.solve(*factors, phi(t, q))
    *factors, ratio = qr.factor(phi_q(t, q))
    q_dot = qr.solve(*factors, nu(t, q))
    q_ddot = qr.solve(*factors, gamma(t, q, q_dot))
    lam = qr.solve_transposed(*factors, forces(t, q, q_dot) - ca.mtimes(mass(q), q_ddot))
    residual = phi(t, q)
    worst = ca.mmax(ca.fabs(residual)) if residual.numel() else sym(1, 1)
    extra = [d] if d.numel() else []
    return ca.Function("prescribed_step", [s, u, *extra],
                       [ca.vertcat(q, q_dot, q_ddot), ca.vertcat(lam, worst, ratio)],
                       ["s", "u", *["d"] * len(extra)], ["s_next", "checks"])


def grid(step_function: ca.Function, rows: int) -> tuple[ca.Function, int]:
    """step mapped over `rows` rows: (s0 (3n), u (2 x padded)) -> (states (3n x padded),
    checks (.. x padded)), and the padded length (a multiple of CHUNK)."""
    inner = step_function.mapaccum("prescribed_chunk", CHUNK)
    outer = -(-rows // CHUNK)
    return inner.mapaccum("prescribed_grid", outer), outer * CHUNK
