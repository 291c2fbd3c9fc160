"""numerics.element_sums: a sum of element kernels, and its Jacobian assembled from the kernels'
own,
equal the same sum written out in SX (outputs that overlap add up, dropped outputs and padded
inputs take no part), whatever the blocks the Jacobian is cut into."""

import casadi as ca
import numpy as np

from casmech.numerics.element_sums import DROPPED, ElementSum, Group, add_into


def _kernel() -> ca.Function:
    y, d = ca.SX.sym("y", 3), ca.SX.sym("d", 2)
    return ca.Function("k", [y, d], [ca.vertcat(y[0] * y[1] * d[0], ca.sin(y[2]) + d[1],
                                                y[0] ** 2)])


N_U, N_ROWS = 5, 4
PADDING = ca.DM([7.0])  # u[5] reads 7: a constant the Jacobian leaves out
INPUTS = np.array([[0, 1, 2], [2, 3, 5], [4, 0, 1]])
OUTPUTS = np.array([[0, 1, DROPPED], [1, 2, 3], [3, 3, 0]])
DATA = ca.DM([[1.0, 2.0, -1.0], [0.5, 0.0, 3.0]])


def _written_out(u):
    k, padded = _kernel(), ca.vertcat(u, PADDING)
    r = [0] * N_ROWS
    for i in range(3):
        out = k(padded[INPUTS[i].tolist()], DATA[:, i])
        for o in range(3):
            if OUTPUTS[i, o] != DROPPED:
                r[OUTPUTS[i, o]] += out[o]
    return ca.vertcat(*r)


def test_value_and_jacobian_blocks_equal_the_written_out_sum():
    elements = ElementSum(N_ROWS, N_U, (Group(_kernel(), INPUTS, OUTPUTS, DATA),), PADDING)
    u_mx, u_sx = ca.MX.sym("u", N_U), ca.SX.sym("u", N_U)
    value = ca.Function("v", [u_mx], [elements.value(u_mx)])
    blocks = ca.Function("b", [u_mx], elements.jacobian(u_mx, ((0, 2), (2, 4)), ((0, 3), (3, 5))))
    want = ca.Function("w", [u_sx], [_written_out(u_sx), ca.jacobian(_written_out(u_sx), u_sx)])
    for seed in range(3):
        u = np.random.default_rng(seed).uniform(-1, 1, N_U)
        r, jac = (np.array(m.full()) for m in want(u))
        # the same operations, summed in another order
        np.testing.assert_allclose(np.array(value(u).full()).ravel(), r.ravel(), rtol=1e-15,
                                   atol=1e-15)
        got = [np.array(ca.densify(b).full()) for b in blocks.call([u])]
        for k, (rows, cols) in enumerate([(s0, s1) for s0 in ((0, 2), (2, 4))
                                          for s1 in ((0, 3), (3, 5))]):
            np.testing.assert_allclose(got[k], jac[slice(*rows), slice(*cols)], rtol=1e-15,
                                       atol=1e-15)


def test_add_into_adds_duplicates():
    values = ca.MX.sym("v", 4)
    out = ca.Function("f", [values], [add_into(3, [(values, [2, 0, 2, 1])])])
    np.testing.assert_array_equal(np.array(out([1.0, 2.0, 3.0, 4.0]).full()).ravel(),
                                  [2.0, 4.0, 4.0])
