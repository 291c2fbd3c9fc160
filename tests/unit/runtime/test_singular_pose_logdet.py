"""runtime.singular_poses.unit_gram_logdet against singular values of the unit rows of Phi_q
(NumPy's SVD, row by row), including a row set that is dependent at every pose."""

import numpy as np
import pytest

import casmech
from casmech.runtime import singular_poses
from casmech.runtime.singular_poses import logdet_function, unit_gram_logdet
from tests.conftest import MODELS
from tests.helpers.reference_data import VALIDATION_MODELS

A02 = VALIDATION_MODELS / "iftomm_a02_four_bar_N2.yaml"


def _svd_logdet(functions, times, q, rows) -> np.ndarray:
    out = []
    for t, row in zip(times, q, strict=True):
        jacobian = np.array(functions["phi_q"](t, row))[rows]
        unit = jacobian / np.linalg.norm(jacobian, axis=1, keepdims=True)
        out.append(2.0 * np.sum(np.log(np.linalg.svd(unit, compute_uv=False))))
    return np.array(out)


def test_unit_gram_logdet_is_twice_the_log_singular_values_of_the_unit_rows():
    functions = casmech.compile(casmech.load(MODELS / "bricard.yaml"))
    result = casmech.analyze(functions, "dynamics", t_end=0.2, rtol=1e-6, atol=1e-8)
    times, q = np.asarray(result.times), np.asarray(result.q)
    m = functions["phi_q"].size1_out(0)
    independent = list(casmech.check(functions)[0].independent)
    assert 0 < len(independent) < m  # Bricard's rows are redundant: both paths below
    # the Cholesky factor's log-determinant against the SVD's: rounding of a product of
    # about 30 singular values of order one
    np.testing.assert_allclose(unit_gram_logdet(functions, times, q, independent),
                               _svd_logdet(functions, times, q, independent),
                               rtol=0, atol=1e-9)
    # every row: dependent at every pose, so no Cholesky factor; slogdet's value is that of a
    # numerically singular matrix, far below the independent rows'
    every = unit_gram_logdet(functions, times, q, list(range(m)))
    assert np.all(every < np.min(unit_gram_logdet(functions, times, q, independent)) - 20)


def _slogdet(functions, times, q, rows) -> np.ndarray:
    """NumPy's slogdet of each row's unit rows' Gram matrix (LU, independent of LDL)."""
    out = []
    for t, row in zip(times, q, strict=True):
        jacobian = np.array(functions["phi_q"](t, row))[rows]
        unit = jacobian / np.linalg.norm(jacobian, axis=1, keepdims=True)
        sign, logdet = np.linalg.slogdet(unit @ unit.T)
        assert sign == 1
        out.append(logdet)
    return np.array(out)


def _through_a_flat_pose(functions):
    """A02 (N = 2) over its first flat pose (0.71 s): the rows and the independent rows."""
    result = casmech.analyze(functions, "dynamics", t_end=1.0, rtol=1e-8, atol=1e-10)
    times, q = np.asarray(result.times), np.asarray(result.q)
    return times, q, [int(k) for k in casmech.check(functions)[0].independent]


def test_the_ldl_log_determinant_is_slogdet_of_the_unit_gram_matrices_through_a_flat_pose():
    functions = casmech.compile(casmech.load(A02), mode="interpreted")
    times, q, rows = _through_a_flat_pose(functions)
    logdet = logdet_function(functions["phi_q"], rows)
    got = np.array([float(logdet(t, row)) for t, row in zip(times, q, strict=True)])
    want = _slogdet(functions, times, q, rows)
    # the run passes the flat pose: some row's unit Gram determinant is ~1e-8 of its t0 value
    assert np.min(want) < want[0] - np.log(1e6)
    # LDL against LU of the same matrices: roundoff of the factors, ~eps times the condition
    # number (~1e8 at the row nearest the flat pose) on a log-determinant of order 10
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-6)
    away = want > want[0] - 1  # rows away from the flat pose: well conditioned
    np.testing.assert_allclose(got[away], want[away], rtol=0, atol=1e-11)  # roundoff


@pytest.mark.slow  # builds the bundle's C library and the log-determinant's
def test_a_compiled_bundle_computes_them_compiled_as_slogdet_does(monkeypatch):
    functions = casmech.compile(casmech.load(A02), mode="compiled")
    times, q, rows = _through_a_flat_pose(functions)
    dense = []
    monkeypatch.setattr(singular_poses, "_dense_logdet", lambda *args: dense.append(args))
    got = unit_gram_logdet(functions, times, q, rows)
    assert dense == []  # every row by the compiled function (finite), none by NumPy's path
    monkeypatch.undo()
    want = _slogdet(functions, times, q, rows)
    assert np.min(want) < want[0] - np.log(1e6)
    # as the interpreted test above: roundoff of the factors near the flat pose
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-6)


def test_rows_the_compiled_function_leaves_not_finite_come_from_numpys_path(monkeypatch):
    functions = casmech.compile(casmech.load(MODELS / "bricard.yaml"), mode="interpreted")
    result = casmech.analyze(functions, "dynamics", t_end=0.05, rtol=1e-6, atol=1e-8)
    times, q = np.asarray(result.times), np.asarray(result.q)
    rows = list(casmech.check(functions)[0].independent)
    numpy = unit_gram_logdet(functions, times, q, rows)  # interpreted: NumPy's path
    stub = np.full(len(times), -1.0)
    stub[[1, 3]] = [np.nan, -np.inf]  # a pivot not positive, a product underflowed
    monkeypatch.setattr(singular_poses, "_compiled", lambda *args: lambda t, x: stub.copy())
    got = unit_gram_logdet(functions, times, q, rows)
    np.testing.assert_array_equal(got[[0, 2, 4]], -1.0)  # the compiled values, as they are
    np.testing.assert_array_equal(got[[1, 3]], numpy[[1, 3]])  # the same path, bit for bit
