"""numerics.instances: a kernel evaluated inline over its instances (one mapped call on SX)
gives, instance by instance, the expressions of the kernel called on that instance alone."""

import casadi as ca
import numpy as np
import pytest

from casmech.numerics import instances


def _kernel() -> ca.Function:
    """Two inputs (a 3 x 1 state of its own, a 2 x 1 value that may be shared), two outputs,
    with constants that fold and a product that vanishes."""
    x, c = ca.SX.sym("x", 3), ca.SX.sym("c", 2)
    return ca.Function("k", [x, c], [ca.vertcat(ca.sin(x[0]) * c[0] + 0 * x[1], x[2] ** 2),
                                     ca.dot(x[:2], c) * 1.0 + 2.0 * 3.0])


@pytest.mark.parametrize("count", [0, 1, 5])
@pytest.mark.parametrize("shared", [False, True])
def test_inline_over_instances_equals_each_instance_called_alone(count, shared):
    kernel = _kernel()
    x = ca.SX.sym("X", 3, count)
    c = ca.SX.sym("C", 2, 1 if shared else count)
    got = instances.inline(kernel, count, [x, c])
    assert [o.shape for o in got] == [(2, count), (1, count)]
    alone = [kernel.call([x[:, i], c[:, 0 if shared else i]]) for i in range(count)]
    want = [ca.horzcat(*[a[o] for a in alone]) if count else ca.SX(got[o].size1(), 0)
            for o in range(2)]
    f = ca.Function("f", [x, c], got)
    g = ca.Function("g", [x, c], want)
    # the same kernel graph expanded per instance: the same instructions
    assert f.n_instructions() == g.n_instructions()
    rng = np.random.default_rng(6)
    args = [rng.uniform(-2, 2, x.shape), rng.uniform(-2, 2, c.shape)]
    for a, b in zip(f.call(args), g.call(args), strict=True):
        np.testing.assert_array_equal(np.array(a), np.array(b))  # identical arithmetic
