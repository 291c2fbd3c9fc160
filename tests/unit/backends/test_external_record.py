"""backends.external_record: the library of each external casmech loads and the binding of
each function it binds to the model data, found by any wrapper of the function and by no other
function."""

import gc

import casadi as ca
import numpy as np
import pytest

from casmech.backends import external_record


def _sx(name: str = "f") -> ca.Function:
    x = ca.SX.sym("x", 2)
    return ca.Function(name, [x], [2 * x])


@pytest.fixture(scope="module")
def loaded(tmp_path_factory):
    """Two functions compiled and loaded through casmech (backends.load records them)."""
    from casmech.backends import build
    from casmech.backends.library import compile_functions

    if not build.available(build.Toolchain()):
        pytest.skip("no C compiler")
    x, d = ca.SX.sym("x", 2), ca.SX.sym("d", 3)
    return compile_functions({"g": _sx("g"), "h": ca.Function("h", [x, d], [x * ca.sum1(d)])},
                             root=tmp_path_factory.mktemp("cache"))


def test_an_external_loaded_by_casmech_names_its_library(loaded):
    path = external_record.library(loaded["g"])
    assert path is not None and path.is_file() and path.is_absolute()
    assert external_record.library(loaded["h"]) == path  # one library holds both
    assert external_record.binding(loaded["g"]) is None


def test_the_record_is_found_through_another_wrapper_of_the_function(loaded):
    """CasADi hands out a new Python wrapper of a function an MX graph calls: its __hash__ is
    the shared object's, so the record is found through it."""
    x = ca.MX.sym("x", 2)
    caller = ca.Function("caller", [x], [loaded["g"](x)])
    [inner] = caller.find_functions()
    assert inner is not loaded["g"] and inner.__hash__() == loaded["g"].__hash__()
    assert external_record.library(inner) == external_record.library(loaded["g"])
    assert external_record.library(caller) is None


def test_functions_casmech_did_not_record_have_no_entry(loaded):
    path = external_record.library(loaded["g"])
    for function in (_sx(), ca.external("g", str(path))):  # an SX function; a user's external
        assert external_record.library(function) is None
        assert external_record.binding(function) is None


def test_a_bound_function_names_what_it_calls_and_d(loaded):
    from casmech.backends.parametric import bind

    d = np.array([0.5, 1.0, 2.0])
    bound = bind(loaded["h"], d)
    inner, values = external_record.binding(bound)
    assert inner is loaded["h"]
    np.testing.assert_array_equal(values, d)
    # bind's call is the function at d (x * (0.5 + 1 + 2))
    np.testing.assert_array_equal(np.array(bound([1.0, -2.0])).ravel(), [3.5, -7.0])
    assert external_record.library(bound) is None


def test_an_entry_lasts_as_long_as_the_wrapper_handed_out(tmp_path):
    """Once the recorded wrapper is collected, another wrapper of the same object finds no
    entry (its object may be freed then, its address reused by another function)."""
    function = _sx()
    other = ca.Function(function)  # a second wrapper of the same object
    external_record.loaded(function, tmp_path / "f.so")
    assert external_record.library(other) == tmp_path / "f.so"
    del function
    gc.collect()
    assert external_record.library(other) is None
