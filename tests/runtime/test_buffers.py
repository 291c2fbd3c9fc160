"""runtime.buffers: a buffered call returns what the ordinary call returns."""

import casadi as ca
import numpy as np

from casmech.runtime.buffers import BufferedCall

RNG = np.random.default_rng(5)


def test_dense_outputs_equal_the_ordinary_call():
    x, u = ca.SX.sym("x", 3), ca.SX.sym("u", 2, 4)
    f = ca.Function("f", [x, u], [ca.mtimes(x, ca.sum1(u)), ca.vertcat(ca.sumsqr(x), u[1, 2])])
    call = BufferedCall(f)
    assert call.dense
    a, b = RNG.normal(size=3), RNG.normal(size=(2, 4))
    got, want = call(a, b), f(a, b)
    for g, w in zip(got, want, strict=True):
        # the same compiled operations on the same numbers
        np.testing.assert_allclose(g, np.array(w), rtol=0, atol=0)


def test_sparse_output_falls_back_to_the_ordinary_call():
    x = ca.SX.sym("x", 3)
    f = ca.Function("f", [x], [ca.diag(x)])  # a sparse 3x3 output
    call = BufferedCall(f)
    assert not call.dense
    a = RNG.normal(size=3)
    (got,) = call(a)
    np.testing.assert_allclose(got, np.diag(a), rtol=0, atol=0)  # exact: no arithmetic
