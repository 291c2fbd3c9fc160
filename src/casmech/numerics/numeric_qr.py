"""Numeric sparse QR: least squares, minimum norm, row independence, for sparse CasADi DMs.

The numeric counterpart of numerics.sparse_qr for matrices evaluated once (assembly, rank
checks), where building a symbolic factorization would cost more than it saves. CasADi's
symbolic analysis (Sparsity.qr_sparse: T. Davis' Householder QR with an optional fill-reducing
column order) gives the patterns; the numeric factorization below is its algorithm
(casadi_qr) in NumPy, one Python step per nonzero of R. (CasADi's own qr_sparse on DM returned
inf/NaN factors for a nonsingular 21 x 21 Phi_q of models/slider_crank.yaml.) Work and memory
follow the fill of the factors, not m n: for an N-link chain's Phi_q^T in the order
checks.structure scans, R grows ~N and the Householder vectors ~N^2 with a small constant
(1.2 M nonzeros for N = 512).

    qr = NumericQR(a)              # a: casadi.DM, m x n with m >= n
    qr.solve(b)                    # least squares of a x = b (full column rank)
    qr.solve_transposed(c)         # minimum norm of a^T y = c
    qr.diagonal()                  # |R_kk| in the factor's column order (qr.columns)

`order=False` keeps a's column order (k-th diagonal = distance of column k from the span of
the columns before it, while those are independent); the default reorders for fill.

Small matrices go to LAPACK instead, up to the sizes of a core.options.LinearAlgebra (where
LAPACK beats the factorization here, one Python step per nonzero of R; the defaults are where
the two cost the same on the benchmark chains: docs/decisions/sparse-rank-and-qr.md).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.core.options import LinearAlgebra

EPS = np.finfo(float).eps
LIMITS = LinearAlgebra()  # the defaults (core.options)


class NumericQR:
    def __init__(self, a: ca.DM, order: bool = True):
        self.m, self.n = a.shape
        if self.m < self.n:
            raise ValueError(f"{self.m} x {self.n} has more columns than rows")
        sp_v, sp_r, prinv, columns = a.sparsity().qr_sparse(order)
        self.prinv, self.columns = np.array(prinv, int), np.array(columns, int)
        self.rows = sp_v.size1()  # m, plus fictitious rows when a is structurally deficient
        self.v_colind, self.v_row = np.array(sp_v.colind()), np.array(sp_v.row())
        self.r_colind, self.r_row = np.array(sp_r.colind()), np.array(sp_r.row())
        self.v = np.zeros(sp_v.nnz())
        self.r = np.zeros(sp_r.nnz())
        self.beta = np.zeros(self.n)
        self._factor(a)

    def _v(self, k):
        span = slice(self.v_colind[k], self.v_colind[k + 1])
        return self.v_row[span], self.v[span]

    def _factor(self, a: ca.DM) -> None:
        """casadi_qr: column by column, the earlier reflections that reach it, then its own."""
        colind, row = a.sparsity().colind(), np.array(a.sparsity().row(), int)
        values = np.array(a.nonzeros())
        x = np.zeros(self.rows)
        for c, column in enumerate(self.columns):
            span = slice(colind[column], colind[column + 1])
            x[self.prinv[row[span]]] = values[span]
            for k in range(self.r_colind[c], self.r_colind[c + 1] - 1):  # above the diagonal
                r = self.r_row[k]
                rows, v = self._v(r)
                x[rows] -= (self.beta[r] * (v @ x[rows])) * v
                self.r[k], x[r] = x[r], 0.0
            span = slice(self.v_colind[c], self.v_colind[c + 1])
            rows = self.v_row[span]
            column_v = x[rows].copy()
            x[rows] = 0.0
            self.r[self.r_colind[c + 1] - 1] = _house(column_v, self.beta, c)
            self.v[span] = column_v

    def diagonal(self) -> np.ndarray:
        return np.abs(self.r[self.r_colind[1:] - 1]) if self.n else np.zeros(0)

    def _reflect(self, w: np.ndarray, order) -> np.ndarray:
        for k in order:
            rows, v = self._v(k)
            w[rows] -= (self.beta[k] * (v @ w[rows])) * v
        return w

    def _triangular(self, w: np.ndarray, transposed: bool) -> np.ndarray:
        """R z = w (backward) or R^T z = w (forward), R upper triangular by columns."""
        colind, rows, values = self.r_colind, self.r_row, self.r
        if transposed:
            for c in range(self.n):
                span = slice(colind[c], colind[c + 1] - 1)
                w[c] = (w[c] - values[span] @ w[rows[span]]) / values[colind[c + 1] - 1]
        else:
            for c in reversed(range(self.n)):
                w[c] /= values[colind[c + 1] - 1]
                span = slice(colind[c], colind[c + 1] - 1)
                w[rows[span]] -= values[span] * w[c]
        return w

    def solve(self, b) -> np.ndarray:
        """x = Pc^T R^-1 [Q^T Pr b]_(1:n)."""
        w = np.zeros(self.rows)
        w[self.prinv[:self.m]] = np.ravel(b)
        z = self._triangular(self._reflect(w, range(self.n))[:self.n], transposed=False)
        x = np.empty(self.n)
        x[self.columns] = z
        return x

    def solve_transposed(self, c) -> np.ndarray:
        """y = Pr^T Q [R^-T Pc c; 0]: the solution of a^T y = c in the range of a."""
        w = np.zeros(self.rows)
        w[:self.n] = self._triangular(np.array(np.ravel(c)[self.columns], float),
                                      transposed=True)
        return self._reflect(w, reversed(range(self.n)))[self.prinv[:self.m]]


def _house(x: np.ndarray, beta: np.ndarray, k: int) -> float:
    """casadi_house: x becomes the Householder vector (x[0] its head), beta[k] its scale;
    returns the diagonal entry of R (the norm of x). Two guards against overflow in beta
    (a Phi_q of models/slider_crank.yaml has entries of 4e-156 beside O(1) ones): x is scaled
    by a power of two near its largest entry (exact), and a tail below roundoff of the head,
    |x[1:]| <= eps |x[0]|, is dropped (as if zero: a backward error of at most eps |x|)."""
    largest = np.max(np.abs(x), initial=0.0)
    if largest == 0.0:  # a zero column: no reflection
        x[0], beta[k] = 1.0, 0.0
        return 0.0
    scale = np.ldexp(1.0, int(np.frexp(largest)[1]))
    x /= scale
    x0, sigma = x[0], float(x[1:] @ x[1:])
    s = np.sqrt(x0 * x0 + sigma)
    if sigma <= (EPS * x0) ** 2:
        x[0], x[1:], beta[k] = 1.0, 0.0, 2.0 * (x0 <= 0)
    else:
        x[0] = x0 - s if x0 <= 0 else -sigma / (x0 + s)
        beta[k] = -1.0 / (s * x[0])
    return s * scale


def norm2(a: ca.DM, iterations: int = 200, tolerance: float = 1e-10,
          limits: LinearAlgebra = LIMITS) -> float:
    """The largest singular value of a sparse a: by a dense SVD when a is small, else by power
    iteration on a^T a from ones (from below; to `tolerance` relative for a well separated one)
    with NumPy products over a's nonzeros."""
    if a.nnz() == 0:
        return 0.0
    m, n = a.size1(), a.size2()
    if m * n <= limits.dense_norm_entries:
        return float(np.linalg.norm(np.array(a), 2))
    rows, cols = (np.asarray(index) for index in a.sparsity().get_triplet())
    values = np.array(a.nonzeros())
    x, estimate = np.ones(n) / np.sqrt(n), 0.0
    for _ in range(iterations):
        y = np.bincount(cols, values * np.bincount(rows, values * x[cols], minlength=m)[rows],
                        minlength=n)
        size = np.linalg.norm(y)
        if size == 0.0:
            return 0.0
        x, previous, estimate = y / size, estimate, np.sqrt(size)
        if abs(estimate - previous) <= tolerance * estimate:
            break
    return float(estimate)


def independent_rows(a: ca.DM, tolerance: float, scale: float,
                     limits: LinearAlgebra = LIMITS) -> list[bool]:
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
        diagonal = _distances(a[candidates, :].T, limits)
        small = [k for k in range(start, len(candidates)) if not diagonal[k] > tolerance * scale]
        if small:  # drop the first dependent row, factor the others again
            keep[kept.pop(small[0])] = False
            start = small[0]
            continue
        for k in kept[len(candidates):]:  # the candidates span every coordinate
            keep[k] = False
        break
    return keep


def _distances(a: ca.DM, limits: LinearAlgebra) -> np.ndarray:
    """|R_kk| of the QR of a in its own column order: by LAPACK up to dense_qr_entries."""
    if a.numel() <= limits.dense_qr_entries:
        return np.abs(np.diag(np.linalg.qr(np.array(a), mode="r")))
    return NumericQR(a, order=False).diagonal()


def _dense_full_rank(a: np.ndarray, b: np.ndarray, full_rank: float) -> np.ndarray | None:
    """lstsq's answer by LAPACK's QR where a has full rank (None otherwise): of a^T when a is
    wide (the minimum-norm solution), of a when tall (least squares)."""
    wide = a.shape[0] <= a.shape[1]
    q, r = np.linalg.qr(a.T if wide else a)
    diagonal = np.abs(np.diag(r))
    if not diagonal.min() > full_rank * diagonal.max():
        return None
    return q @ np.linalg.solve(r.T, b) if wide else np.linalg.solve(r, q.T @ b)


def lstsq(a: ca.DM, b, tolerance: float = 1e-9,
          limits: LinearAlgebra = LIMITS) -> np.ndarray:
    """numpy.linalg.lstsq(a, b)[0]: by NumPy's SVD up to dense_entries, its QR up to
    dense_qr_entries where a has full rank (`limits`); otherwise, for a sparse a: full row
    rank: the minimum-norm solution (QR of a^T); full column rank: least squares (QR of a).
    Otherwise the rows D within tolerance * |a|_2 of the span of earlier rows I are taken as
    a_D = C a_I exactly (C by least squares); then a x = b in least squares is a_I x = y with
    (I + C^T C) y = b_I + C^T b_D (solved by Woodbury: D is small), and x the minimum-norm
    solution of that: lstsq's answer for a matrix of that rank."""
    m, n = a.shape
    b = np.ravel(b).astype(float)
    if m == 0 or n == 0:
        return np.zeros(n)
    if a.numel() <= limits.dense_entries:
        return np.linalg.lstsq(np.array(a), b, rcond=None)[0]
    if a.numel() <= limits.dense_qr_entries:
        x = _dense_full_rank(np.array(a), b, limits.full_rank)
        if x is not None:
            return x
    qr = NumericQR(a.T) if m <= n else NumericQR(a)
    diagonal = qr.diagonal()
    if diagonal.min() > limits.full_rank * diagonal.max():
        return qr.solve_transposed(b) if m <= n else qr.solve(b)
    keep = np.array(independent_rows(a, tolerance, max(norm2(a, limits=limits), 1.0), limits))
    kept, dropped = np.flatnonzero(keep), np.flatnonzero(~keep)
    if kept.size == 0:
        return np.zeros(n)
    qr = NumericQR(a[kept.tolist(), :].T)
    rows = a[dropped.tolist(), :]
    c = np.array([qr.solve(np.array(rows[k, :]).ravel()) for k in range(dropped.size)])
    c = c.reshape(dropped.size, kept.size)
    y = b[kept] + c.T @ b[dropped]
    y -= c.T @ np.linalg.solve(np.eye(dropped.size) + c @ c.T, c @ y)
    return qr.solve_transposed(y)
