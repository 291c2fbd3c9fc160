"""backends.rk_library: the C entry point of a compiled CasADi function (its library as
backends.external_record recorded it when casmech loaded it), and the functions that have
none."""

import casadi as ca
import numpy as np
import pytest

from casmech.backends import rk_library
from casmech.backends.library import compile_functions


@pytest.fixture(scope="module")
def externals(tmp_path_factory):
    from casmech.backends import build

    if not build.available(build.Toolchain()):
        pytest.skip("no C compiler")
    t, x, p = ca.SX.sym("t"), ca.SX.sym("x", 2), ca.SX.sym("p", 3)
    plain = ca.Function("plain", [t, x], [ca.vertcat(x[1], -x[0] + t)], ["t", "x"], ["ode"])
    extra = ca.Function("extra", [t, x, p], [x * ca.sum1(p)], ["t", "x", "p"], ["ode"])
    return compile_functions({"plain": plain, "extra": extra},
                             root=tmp_path_factory.mktemp("cache"))


def test_the_library_of_an_external(externals):
    entry = rk_library.entry(externals["plain"])
    assert entry is not None and (entry.struct.i_t, entry.struct.i_x) == (0, 1)


def test_functions_without_an_entry_point(externals):
    t, x = ca.SX.sym("t"), ca.SX.sym("x", 2)
    assert rk_library.entry(ca.Function("sx", [t, x], [x], ["t", "x"], ["ode"])) is None
    # an input besides t and x that holds numbers: not called from C (runtime.dop853's Python
    # path takes it)
    assert rk_library.entry(externals["extra"]) is None


def test_an_external_casmech_did_not_load_takes_the_python_path(externals):
    """A casadi.external a user loads from the same library: no record, no entry point;
    runtime.dop853 integrates it in Python, to the same solution."""
    from casmech.backends import external_record
    from casmech.runtime.dop853 import Dop853

    path = external_record.library(externals["plain"])
    theirs = ca.external("plain", str(path))
    assert rk_library.entry(theirs) is None
    rk = Dop853(theirs, 1e-10, 1e-12)
    assert not rk.compiled
    times = np.linspace(0.5, 3.0, 6)
    # rtol 1e-10 over ~20 steps of a smooth solution of size ~3
    np.testing.assert_allclose(rk(0.0, times, [1.0, 0.0])[0],
                               np.cos(times) + times - np.sin(times), rtol=0, atol=1e-8)


def test_the_driver_builds_and_runs(externals):
    """The driver through runtime.dop853 on x'' = -x + t from (1, 0): x = cos t + t - sin t."""
    from casmech.runtime.dop853 import Dop853

    rk = Dop853(externals["plain"], 1e-10, 1e-12)
    assert rk.compiled
    times = np.linspace(0.5, 3.0, 6)
    states = rk(0.0, times, [1.0, 0.0])
    # rtol 1e-10 over ~20 steps of a smooth solution of size ~3
    np.testing.assert_allclose(states[0], np.cos(times) + times - np.sin(times), rtol=0,
                               atol=1e-8)


def test_a_function_bound_to_its_data_is_reached_through_its_external(externals):
    """backends.parametric.bind's form: the external called with a constant last input."""
    from casmech.backends.parametric import bind

    d = np.array([0.5, 1.0, 2.0])
    bound = bind(externals["extra"], d)
    entry = rk_library.entry(bound)
    assert entry is not None and entry.struct.i_x == 1
    np.testing.assert_array_equal(entry.fixed[2], d)
    # the driver over it: x' = 3.5 x, so x = exp(3.5 t) (rtol 1e-10 over 1.75 e-folds)
    from casmech.runtime.dop853 import Dop853

    rk = Dop853(bound, 1e-10, 1e-12)
    assert rk.compiled
    states = rk(0.0, [0.25, 0.5], [1.0, 2.0])
    np.testing.assert_allclose(states, np.outer([1.0, 2.0], np.exp(3.5 * np.array([0.25, 0.5]))),
                               rtol=1e-8, atol=0)
    # the same form built by other code: not recorded, so no entry point
    t, x = ca.MX.sym("t"), ca.MX.sym("x", 2)
    other = ca.Function("other", [t, x], [externals["extra"](t, x, ca.DM(d))], ["t", "x"],
                        ["ode"])
    assert rk_library.entry(other) is None
