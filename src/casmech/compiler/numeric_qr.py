"""Numeric sparse QR (CasADi's qr_sparse on DM): least squares, minimum norm, row independence.

The numeric counterpart of compiler.sparse_qr for matrices evaluated once (assembly, rank
checks), where building a symbolic factorization would cost more than it saves. Work and
memory follow the fill of the factors, not m n: for an N-link chain's Phi_q^T the R factor
grows ~N and the Householder vectors ~N^2 with a small constant (1.2 M nonzeros, 0.05 s for
N = 512).

    qr = NumericQR(a)              # a: casadi.DM, m x n with m >= n
    qr.solve(b)                    # least squares of a x = b (full column rank)
    qr.solve_transposed(c)         # minimum norm of a^T y = c
    qr.diagonal()                  # |R_kk| in the factor's column order (qr.columns)

`order=False` keeps a's column order (k-th diagonal = distance of column k from the span of
the columns before it, while those are independent); the default reorders for fill.
"""

from __future__ import annotations

import casadi as ca
import numpy as np


class NumericQR:
    def __init__(self, a: ca.DM, order: bool = True):
        self.m, self.n = a.shape
        if self.m < self.n:
            raise ValueError(f"{self.m} x {self.n} has more columns than rows")
        v, self.r, beta, self.prinv, self.columns = ca.qr_sparse(a, order)
        self.rows = v.size1()  # m plus CSparse's fictitious rows of a structurally rank-deficient a
        self.beta = np.array(beta).ravel()
        self.v_colind = np.array(v.sparsity().colind())
        self.v_row = np.array(v.sparsity().row())
        self.v_values = np.array(v.nonzeros())
        self.top = self.r[:self.n, :self.n]

    def diagonal(self) -> np.ndarray:
        return np.abs(np.array(ca.diag(self.top)).ravel())

    def _reflect(self, w: np.ndarray, order) -> np.ndarray:
        for k in order:
            span = slice(self.v_colind[k], self.v_colind[k + 1])
            rows, values = self.v_row[span], self.v_values[span]
            w[rows] -= (self.beta[k] * (values @ w[rows])) * values
        return w

    def solve(self, b) -> np.ndarray:
        """x = Pc^T R^-1 [Q^T Pr b]_(1:n)."""
        w = np.zeros(self.rows)
        w[np.asarray(self.prinv[:self.m])] = np.ravel(b)
        w = self._reflect(w, range(self.n))
        z = np.array(ca.solve(self.top, ca.DM(w[:self.n]))).ravel()
        x = np.empty(self.n)
        x[np.asarray(self.columns)] = z
        return x

    def solve_transposed(self, c) -> np.ndarray:
        """y = Pr^T Q [R^-T Pc c; 0]: the solution of a^T y = c in the range of a."""
        z = np.array(ca.solve(self.top.T, ca.DM(np.ravel(c)[np.asarray(self.columns)]))).ravel()
        w = np.zeros(self.rows)
        w[:self.n] = z
        w = self._reflect(w, reversed(range(self.n)))
        return w[np.asarray(self.prinv[:self.m])]


def norm2(a: ca.DM, iterations: int = 200, tolerance: float = 1e-10) -> float:
    """The largest singular value of a sparse a, by power iteration on a^T a from ones (from
    below; to `tolerance` relative for a well separated one)."""
    if a.nnz() == 0:
        return 0.0
    at = a.T
    x, estimate = np.ones(a.size2()) / np.sqrt(a.size2()), 0.0
    for _ in range(iterations):
        y = np.array(ca.mtimes(at, ca.mtimes(a, x))).ravel()
        size = np.linalg.norm(y)
        if size == 0.0:
            return 0.0
        x, previous, estimate = y / size, estimate, np.sqrt(size)
        if abs(estimate - previous) <= tolerance * estimate:
            break
    return float(estimate)


def independent_rows(a: ca.DM, tolerance: float, scale: float) -> list[bool]:
    """Greedy in row order: is row k of a farther than tolerance * scale from the span of the
    rows kept before it? QR of a^T in row order (no reordering): |R_kk| is that distance while
    every earlier row is independent; at the first row that is not, the row is dropped and the
    rest factored again (one factorization per dependent row, and one)."""
    keep = [a.size2() > 0] * a.size1()
    kept = list(range(a.size1()))
    start = 0  # the rows kept[:start] are decided
    while start < len(kept):
        candidates = kept[:a.size2()]  # a^T must not be wider than tall
        if not candidates:  # no coordinates: every row is zero
            break
        diagonal = NumericQR(a[candidates, :].T, order=False).diagonal()
        small = [k for k in range(start, len(candidates)) if not diagonal[k] > tolerance * scale]
        if small:  # drop the first dependent row, factor the others again
            keep[kept.pop(small[0])] = False
            start = small[0]
            continue
        for k in kept[len(candidates):]:  # the candidates span every coordinate
            keep[k] = False
        break
    return keep
