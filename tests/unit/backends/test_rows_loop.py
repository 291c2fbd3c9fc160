"""backends.rows_loop: a compiled function over rows in one C loop (c/casmech_rows.c), against
casadi's own evaluation of the same function column by column."""

import casadi as ca
import numpy as np
import pytest

from casmech.backends import rows_loop
from casmech.backends.library import compile_functions


@pytest.fixture(scope="module")
def externals(tmp_path_factory):
    from casmech.backends import build

    if not build.available(build.Toolchain()):
        pytest.skip("no C compiler")
    t, x, z, s = ca.SX.sym("t"), ca.SX.sym("x", 3), ca.SX.sym("z", 0), ca.SX.sym("s", 2)
    rows = ca.Function("rows", [t, x, z, s],
                       [ca.vertcat(ca.sin(x[0]) * s[0] + t, x[1] * x[2]), ca.SX(0, 1),
                        ca.vertcat(x * s[1], t * t, ca.sum1(x))],
                       ["t", "x", "z", "signs"], ["a", "none", "b"])
    d = ca.SX.sym("d", 2)
    with_data = ca.Function("with_data", [t, x, d], [x * d[0] + t * d[1]], ["t", "x", "d"],
                            ["y"])
    return compile_functions({"rows": rows, "with_data": with_data},
                             root=tmp_path_factory.mktemp("cache"))


def _columns(function, *inputs):
    """function over columns by casadi (each input a column per row, or shared)."""
    return [np.array(out) for out in function.map(inputs[0].shape[1])(*inputs)]


def test_rows_as_casadis_own_evaluation(externals):
    function = externals["rows"]
    call = rows_loop.rows_call(function)
    assert call is not None
    rng = np.random.default_rng(3)
    times, states, signs = rng.normal(size=7), rng.normal(size=(7, 3)), np.array([-1.0, 2.0])
    got = call(7, times, states, None, signs)
    want = _columns(function, times[None, :], states.T, np.zeros((0, 7)),
                    np.repeat(signs[:, None], 7, axis=1))
    assert [g.shape for g in got] == [(7, 2), (7, 0), (7, 5)]
    for g, w in zip(got, want, strict=True):  # the same compiled code on the same numbers
        np.testing.assert_array_equal(g, w.T)
    # read-only inputs (whose buffers ctypes cannot view): the same rows
    frozen = [a.copy() for a in (times, states, signs)]
    for a in frozen:
        a.setflags(write=False)
    for g, w in zip(call(7, *frozen[:2], None, frozen[2]), got, strict=True):
        np.testing.assert_array_equal(g, w)  # the same compiled code on the same numbers
    # the outputs are fresh: the next call does not write into them
    before = [g.copy() for g in got]
    call(7, times + 1, states, None, signs)
    for g, b in zip(got, before, strict=True):
        np.testing.assert_array_equal(g, b)


def test_no_rows_and_wrong_shapes(externals):
    call = rows_loop.rows_call(externals["rows"])
    assert [g.shape for g in call(0, np.zeros(0), np.zeros((0, 3)), None, np.ones(2))] == [
        (0, 2), (0, 0), (0, 5)]
    with pytest.raises(ValueError, match="input 1"):
        call(4, np.zeros(4), np.zeros((3, 4)), None, np.ones(2))
    with pytest.raises(TypeError, match="takes 4 inputs"):
        call(4, np.zeros(4), np.zeros((4, 3)))


def test_a_function_bound_to_its_data(externals):
    """backends.parametric.bind's form: the external's last input d read by every row."""
    from casmech.backends.parametric import bind

    d = np.array([0.5, 2.0])
    call = rows_loop.rows_call(bind(externals["with_data"], d))
    assert call is not None
    times, states = np.array([0.0, 1.0, 2.0]), np.arange(9.0).reshape(3, 3)
    (y,) = call(3, times, states)
    # y = 0.5 x + 2 t, exact in binary
    np.testing.assert_array_equal(y, 0.5 * states + 2.0 * times[:, None])


def test_functions_without_an_entry_point(externals):
    from casmech.backends import external_record

    t, x = ca.SX.sym("t"), ca.SX.sym("x", 2)
    assert rows_loop.rows_call(ca.Function("sx", [t, x], [x], ["t", "x"], ["y"])) is None
    # a casadi.external a user loads from the same library: not recorded by casmech
    path = external_record.library(externals["rows"])
    assert rows_loop.rows_call(ca.external("rows", str(path))) is None


def test_a_chain_of_parts_over_rows(externals, tmp_path):
    """A function compiled as a chain of parts (backends.split) and recorded as such
    (rows_loop.chained): the parts in turn over all rows compute the function's rows
    (`externals`: skipped without a C compiler)."""
    from casmech.backends.split import joined, parts

    t, x, z, s = ca.SX.sym("t"), ca.SX.sym("x", 3), ca.SX.sym("z", 0), ca.SX.sym("s", 2)
    inline = ca.Function("rows", [t, x, z, s], [ca.cos(x[0] * t) + s[0], ca.SX(0, 1),
                                                 ca.vertcat(x * ca.sin(t), s[1] * x[2])],
                         ["t", "x", "z", "signs"], ["a", "none", "b"])
    names = ("chain_0", "chain_1", "chain_2")
    built = compile_functions(dict(zip(names, parts(inline, names), strict=True)),
                              root=tmp_path)
    chain = [built[name] for name in names]
    whole = rows_loop.chained(joined(chain, "rows"), chain)
    call = rows_loop.rows_call(whole)
    assert call is not None and len(call.entries) == 3
    rng = np.random.default_rng(4)
    for rows in (6, 2, 9):  # the shared values' buffers grown and reused
        times, states, signs = rng.normal(size=rows), rng.normal(size=(rows, 3)), rng.normal(
            size=2)
        want = _columns(whole, times[None, :], states.T, np.zeros((0, rows)),
                        np.repeat(signs[:, None], rows, axis=1))
        for g, w in zip(call(rows, times, states, None, signs), want, strict=True):
            # the same compiled parts on the same numbers
            np.testing.assert_array_equal(g, w.T)
    # the same parts joined again but not recorded: an MX function without an entry point
    assert rows_loop.rows_call(joined(chain, "rows")) is None


def test_a_vector_given_again_is_read_again(externals):
    """A vector every row reads, given again as the same object (its address kept): its
    values as they are at each call, and whatever was given in its place in between."""
    function = externals["rows"]
    call = rows_loop.rows_call(function)
    rng = np.random.default_rng(5)
    times, states = rng.normal(size=4), rng.normal(size=(4, 3))
    signs = np.array([1.0, -1.0])

    def want(s):
        return call(4, times, states, None, np.array(s))  # a fresh array: no kept address

    first = call(4, times, states, None, signs)
    for g, w in zip(first, want([1.0, -1.0]), strict=True):
        np.testing.assert_array_equal(g, w)  # the same compiled code on the same numbers
    signs[:] = [2.0, 3.0]  # the same object, new values
    for g, w in zip(call(4, times, states, None, signs), want([2.0, 3.0]), strict=True):
        np.testing.assert_array_equal(g, w)  # the same compiled code on the same numbers
    # another input in its place (rows of their own, none), then the vector again
    per_row = np.tile([5.0, 7.0], (4, 1))
    for g, w in zip(call(4, times, states, None, per_row), want([5.0, 7.0]), strict=True):
        np.testing.assert_array_equal(g, w)  # the same compiled code on the same numbers
    call(4, times, states, None, None)
    for g, w in zip(call(4, times, states, None, signs), want([2.0, 3.0]), strict=True):
        np.testing.assert_array_equal(g, w)  # the same compiled code on the same numbers
    with pytest.raises(ValueError, match="input 3"):
        call(4, times, states, None, np.ones(3))
