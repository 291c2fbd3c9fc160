"""runtime.singular_poses.unit_gram_logdet against singular values of the unit rows of Phi_q
(NumPy's SVD, row by row), including a row set that is dependent at every pose."""

import numpy as np

import casmech
from casmech.runtime.singular_poses import unit_gram_logdet
from tests.conftest import MODELS


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
