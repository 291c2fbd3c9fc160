"""Least squares and minimum-norm solves by CasADi's sparse Householder QR, as SX Functions.

For A (m x n, m >= n, full column rank) `solve` gives the least-squares solution of A x = b
and `solve_transposed` the minimum-norm solution of A^T y = c: what numpy.linalg.lstsq gives
for such an A, so redundant constraint rows (m > n) are handled as the dense code did.
casadi.qr_sparse factors A symbolically over its sparsity (T. Davis' Householder QR with a
fill-reducing column order), so the work and the expression grow with the fill, not with
m n; casadi.qr_solve serves the square case, the rectangular one applies the Householder
reflections here (qr_solve assumes m = n).

The Functions are SX: called with SX arguments they inline, with MX ones (an MX graph over a
compiled bundle) they are called.
"""

from __future__ import annotations

import casadi as ca

from casmech.core.records import record


@record
class SparseQR:
    """factor(A) -> (V, R, beta, pivot_ratio); solve(V, R, beta, b) -> x;
    solve_transposed(V, R, beta, c) -> y. pivot_ratio = min |R_kk| / max |R_kk| (0 for a
    structurally or numerically singular A, and an upper bound of A's inverse condition)."""

    factor: ca.Function
    solve: ca.Function
    solve_transposed: ca.Function


def sparse_qr(sparsity: ca.Sparsity, name: str = "qr") -> SparseQR:
    m, n = sparsity.size1(), sparsity.size2()
    if m < n:
        raise ValueError(f"{name}: {m} x {n} has more columns than rows")
    a = ca.SX.sym("A", sparsity)
    v, r, beta, prinv, pc = ca.qr_sparse(a)
    diagonal = ca.fabs(ca.diag(r[:n, :n]))
    ratio = ca.mmin(diagonal) / ca.mmax(diagonal) if n else ca.SX(1)
    factor = ca.Function(f"{name}_factor", [a], [v, r, beta, ratio],
                         ["A"], ["V", "R", "beta", "pivot_ratio"])
    factors = [ca.SX.sym(label, e.sparsity()) for label, e in (("V", v), ("R", r), ("beta", beta))]
    b, c = ca.SX.sym("b", m), ca.SX.sym("c", n)
    if m == v.size1() == n:
        x = ca.qr_solve(b, *factors, prinv, pc, False)
        y = ca.qr_solve(c, *factors, prinv, pc, True)
    else:
        x = _least_squares(b, *factors, prinv, pc)
        y = _minimum_norm(c, *factors, prinv, pc, m)
    return SparseQR(factor,
                    ca.Function(f"{name}_solve", [*factors, b], [x],
                                ["V", "R", "beta", "b"], ["x"]),
                    ca.Function(f"{name}_solve_transposed", [*factors, c], [y],
                                ["V", "R", "beta", "c"], ["y"]))


def _reflect(w, v, beta, order):
    """Apply the Householder reflections I - beta_k v_k v_k^T to w in the given order."""
    for k in order:
        column = v[:, k]
        w = w - (beta[k] * ca.dot(column, w)) * column
    return w


def _least_squares(b, v, r, beta, prinv, pc):
    """x = Pc^T R^-1 [Q^T Pr b]_(1:n): A = Pr^T Q R Pc (rows permuted by prinv, columns by pc)."""
    n, rows = r.size2(), v.size1()
    w = ca.vertcat(b, ca.SX(rows - b.numel(), 1))[_inverse(prinv)]  # fictitious rows: 0
    w = _reflect(w, v, beta, range(n))
    return ca.solve(r[:n, :n], w[:n])[_inverse(pc)]


def _minimum_norm(c, v, r, beta, prinv, pc, m):
    """y = Pr^T Q [R^-T Pc c; 0]: the solution of A^T y = c in the range of A."""
    n = r.size2()
    z = ca.solve(r[:n, :n].T, c[list(pc)])
    w = ca.vertcat(z, ca.SX(v.size1() - n, 1))
    w = _reflect(w, v, beta, reversed(range(n)))
    return w[list(prinv[:m])]


def _inverse(permutation) -> list[int]:
    inverse = [0] * len(permutation)
    for i, k in enumerate(permutation):
        inverse[k] = i
    return inverse
