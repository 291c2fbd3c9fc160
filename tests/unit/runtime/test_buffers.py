"""runtime.buffers: a buffered call returns what the ordinary call returns."""

import casadi as ca
import numpy as np
import pytest

from casmech.runtime.buffers import BufferedCall, ColumnCall, NamedCall

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


def test_integrator_by_names_equals_the_ordinary_call():
    """An integrator over a grid, inputs by name (the others zero): the ordinary call's
    outputs, and its failure as the same RuntimeError with the solver's flag."""
    x, z, p = ca.SX.sym("x", 2), ca.SX.sym("z"), ca.SX.sym("p")
    problem = {"x": x, "z": z, "p": p, "ode": ca.vertcat(x[1], -p * x[0] + z), "alg": z - 0.5}
    grid = list(np.linspace(0.1, 2.0, 20))
    integrator = ca.integrator("i", "idas", problem, 0.0, grid, {"abstol": 1e-10})
    call = NamedCall(integrator)
    assert call.stats() == {}  # before a call
    got = call(x0=np.array([1.0, 0.0]), z0=np.array([0.5]), p=np.array([4.0]))
    steps = call.stats()["nsteps"]  # the buffered call's own statistics
    want = integrator(x0=[1.0, 0.0], z0=0.5, p=4.0)
    assert steps == integrator.stats()["nsteps"] > 0
    for name in ("xf", "zf"):
        # the same integration of the same numbers
        np.testing.assert_allclose(got[name], np.array(want[name]), rtol=0, atol=0)
    blowing_up = ca.integrator("b", "cvodes", {"x": x, "ode": x * x}, 0.0, [1.0, 2.0],
                               {"max_num_steps": 50})
    with pytest.raises(RuntimeError, match="CV_TOO_MUCH_WORK"):
        NamedCall(blowing_up)(x0=np.ones(2))


@pytest.mark.parametrize("count", [0, 1, 3, 256, 257, 600])
def test_columns_in_blocks_equal_one_mapped_call(monkeypatch, count):
    """Evaluations in blocks (short ones padded) give the one map's outputs, for inputs with
    one or two columns per evaluation and an input shared by all; with a sparse output too."""
    x, m, c = ca.SX.sym("x", 2), ca.SX.sym("m", 2, 2), ca.SX.sym("c", 3)
    f = ca.Function("f", [x, m, c], [ca.vertcat(ca.mtimes(m, x), ca.sum1(c)), ca.diag(x) * c[0]])
    xs, ms, shared = RNG.normal(size=(2, count)), RNG.normal(size=(2, 2 * count)), RNG.normal(
        size=3)
    got = ColumnCall(f)(xs, ms, shared)
    assert [g.shape for g in got] == [(3, count), (2, 2 * count)]
    if count:
        want = f.map(count)(xs, ms, shared)
        for g, w in zip(got, want, strict=True):
            # the same operations on the same numbers, one evaluation at a time
            np.testing.assert_allclose(g, np.array(w), rtol=0, atol=0)


def test_blocks_bounded_by_numbers(monkeypatch):
    """A function with many numbers per evaluation is mapped over fewer columns at a time
    (MAP_ENTRIES), with the same outputs."""
    from casmech.runtime import buffers

    x, c = ca.SX.sym("x", 4), ca.SX.sym("c", 3)
    f = ca.Function("f", [x, c], [ca.vertcat(x * c[0], ca.sum1(c))])
    monkeypatch.setattr(buffers, "MAP_ENTRIES", 30)  # 4 + 3 in, 5 out: 12 a column, 2 a block
    call = ColumnCall(f)
    assert call.block == 2
    xs, shared = RNG.normal(size=(4, 7)), RNG.normal(size=3)
    (got,) = call(xs, shared)
    # the same operations on the same numbers, one evaluation at a time
    np.testing.assert_allclose(got, np.array(f.map(7)(xs, shared)), rtol=0, atol=0)
    assert set(call.maps) == {(2, (1,)), (1, ())}  # blocks of 2, 2, 2 and 1; c shared


def test_each_call_returns_its_own_arrays_and_none_is_zeros(monkeypatch):
    """Bound buffers (small functions) and per-call ones (BOUND_ENTRIES 0) alike: a later
    call leaves an earlier call's outputs as they were; None inputs are zeros, also after a
    call that gave that input."""
    from casmech.runtime import buffers

    x, y = ca.SX.sym("x", 2), ca.SX.sym("y", 2, 3)
    f = ca.Function("f", [x, y], [ca.mtimes(x.T, y), x + ca.sum2(y)])
    for limit in (buffers.BOUND_ENTRIES, 0):
        monkeypatch.setattr(buffers, "BOUND_ENTRIES", limit)
        call = BufferedCall(f)
        assert (call._bound is not None) == bool(limit)
        a, b = RNG.normal(size=2), RNG.normal(size=(2, 3))
        first = call(a, b)
        kept = [np.array(o) for o in first]
        call(2 * a, b)
        for got, want in zip(first, kept, strict=True):
            np.testing.assert_array_equal(got, want)  # untouched by the second call
        for got, want in zip(call(None, b), f(np.zeros(2), b), strict=True):
            # the same operations on the same numbers
            np.testing.assert_allclose(got, np.array(want), rtol=0, atol=0)


def test_only_solvers_are_interruptible():
    """A signal stops casadi's solvers only: their calls (and MX functions calling them)
    mark what they did not write with NaN; plain and mapped expressions need not."""
    from casmech.runtime.buffers import interruptible

    x = ca.SX.sym("x", 2)
    plain = ca.Function("plain", [x], [ca.sin(x)])
    solver = ca.integrator("solver", "cvodes", {"x": x, "ode": -x}, 0.0, [1.0])
    xm = ca.MX.sym("x", 2)
    calling = ca.Function("calling", [xm], [solver(x0=xm)["xf"] + plain(xm)])
    assert not interruptible(plain) and not interruptible(plain.map(4))
    assert not interruptible(ca.Function("mx", [xm], [plain(xm) * 2]))
    assert interruptible(solver) and interruptible(calling) and interruptible(solver.map(3))
    assert not BufferedCall(plain).stoppable and BufferedCall(solver).stoppable
