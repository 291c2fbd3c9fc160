"""numerics.sparse_qr (symbolic, SX Functions) and numerics.numeric_qr (numeric) against
numpy.linalg.lstsq: least squares, minimum norm, rank-deficient matrices, extreme entries."""

import casadi as ca
import numpy as np
import pytest

from casmech.core.options import LinearAlgebra
from casmech.numerics import numeric_qr
from casmech.numerics.sparse_qr import sparse_qr

SHAPES = [(12, 12), (15, 9), (20, 11)]


def sparse_random(rng, m, n, density=0.3):
    """Sparse with a nonzero diagonal, so that it has full column rank."""
    return rng.standard_normal((m, n)) * (rng.random((m, n)) < density) + 3 * np.eye(m, n)


@pytest.mark.parametrize("m, n", SHAPES)
@pytest.mark.parametrize("sym", [ca.SX, ca.MX])
def test_symbolic_solves_equal_lstsq(m, n, sym):
    rng = np.random.default_rng(m + n)
    a = sparse_random(rng, m, n)
    qr = sparse_qr(ca.sparsify(ca.DM(a)).sparsity())
    matrix, b, c = sym.sym("a", qr.factor.sparsity_in(0)), sym.sym("b", m), sym.sym("c", n)
    *factors, ratio = qr.factor(matrix)
    both = ca.Function("both", [matrix, b, c], [qr.solve(*factors, b),
                                                 qr.solve_transposed(*factors, c), ratio])
    b_value, c_value = rng.standard_normal(m), rng.standard_normal(n)  # b not in a's range
    x, y, pivot_ratio = (np.array(v).ravel() for v in both(ca.sparsify(ca.DM(a)), b_value,
                                                           c_value))
    # Householder QR and the SVD-based lstsq on condition ~10 matrices: roundoff
    np.testing.assert_allclose(x, np.linalg.lstsq(a, b_value, rcond=None)[0], rtol=0, atol=1e-13)
    np.testing.assert_allclose(y, np.linalg.lstsq(a.T, c_value, rcond=None)[0], rtol=0,
                               atol=1e-13)
    singular = np.linalg.svd(a, compute_uv=False)
    assert singular[-1] / singular[0] <= pivot_ratio[0] <= 1  # an upper bound of 1 / cond


@pytest.mark.parametrize("m, n", SHAPES)
@pytest.mark.parametrize("order", [True, False])
def test_numeric_solves_equal_lstsq(m, n, order):
    rng = np.random.default_rng(m * n)
    a = sparse_random(rng, m, n)
    qr = numeric_qr.NumericQR(ca.sparsify(ca.DM(a)), order)
    b, c = rng.standard_normal(m), rng.standard_normal(n)
    np.testing.assert_allclose(qr.solve(b), np.linalg.lstsq(a, b, rcond=None)[0], rtol=0,
                               atol=1e-13)  # roundoff on condition ~10
    np.testing.assert_allclose(qr.solve_transposed(c), np.linalg.lstsq(a.T, c, rcond=None)[0],
                               rtol=0, atol=1e-13)
    r = np.linalg.qr(a[:, qr.columns])[1]
    np.testing.assert_allclose(qr.diagonal(), np.abs(np.diag(r)), rtol=1e-13, atol=0)


@pytest.mark.parametrize("m, n", [(10, 16), (16, 10), (12, 12)])
@pytest.mark.parametrize("dense_qr", [0, LinearAlgebra().dense_qr_entries])
def test_numeric_lstsq_of_rank_deficient_matrices(m, n, dense_qr):
    """Rows that are combinations of others (and, for a tall matrix, a repeated column): the
    least-squares solution of least norm, as the SVD gives it, for an inconsistent b (the
    dense QR path sees the rank loss and leaves these to the sparse one)."""
    rng = np.random.default_rng(7 * m + n)
    a = sparse_random(rng, m, n)
    a[3], a[7] = 2 * a[1] - a[0], a[2]
    if m > n:
        a[:, 4] = a[:, 2]
    b = rng.standard_normal(m)
    # the sparse path at this size, or LAPACK's QR (which sees the rank loss)
    limits = LinearAlgebra(dense_entries=0, dense_qr_entries=dense_qr)
    np.testing.assert_allclose(numeric_qr.lstsq(ca.sparsify(ca.DM(a)), b, limits=limits),
                               np.linalg.lstsq(a, b, rcond=None)[0], rtol=0, atol=1e-12)


def test_numeric_factor_of_roundoff_sized_entries():
    """A column whose entries below the head are ~4e-156 (a slider-crank's Phi_q had them)
    overflowed the Householder scale (1 / 1e-312); a zero column gives a zero diagonal."""
    rng = np.random.default_rng(4)
    a = sparse_random(rng, 8, 8)
    a[:, 0] = 0.0
    a[0, 0], a[5, 0], a[6, 0] = 1.0, 3.9e-156, -2.1e-156
    qr = numeric_qr.NumericQR(ca.sparsify(ca.DM(a)), order=False)
    b = rng.standard_normal(8)
    np.testing.assert_allclose(qr.solve(b), np.linalg.solve(a, b), rtol=0, atol=1e-13)
    a[:, 3] = 0.0
    diagonal = numeric_qr.NumericQR(ca.DM(a), order=False).diagonal()
    assert np.isfinite(diagonal).all() and diagonal[3] == 0.0
