"""codegen.compile_functions: arbitrary named casadi Functions compiled into a cached library
keyed by their content. The externals equal the SX functions in value and Jacobian, a DAE
residual comes back as IDAS integrates it (daeF and jacF from its library), and the same
functions a second time build nothing while a changed function builds anew."""

import casadi as ca
import numpy as np
import pytest

from casmech.backends import codegen, library
from tests.helpers.codegen import counted_builds


def _function(gain: float = 2.0) -> ca.Function:
    x, y = ca.SX.sym("x", 3), ca.SX.sym("y")
    return ca.Function("f", [x, y], [ca.vertcat(ca.sin(x[0]) * x[1] + gain * y, x[2] ** 3),
                                     ca.dot(x, x)], ["x", "y"], ["a", "b"])


def _oscillator() -> ca.Function:
    """x' = v, v' = a with alg: a + k x = 0 (k = p): the residual of formulations.dae's shape."""
    t, x, z, p = ca.SX.sym("t"), ca.SX.sym("x", 2), ca.SX.sym("z"), ca.SX.sym("p")
    return ca.Function("oscillator", [t, x, z, p], [ca.vertcat(x[1], z), z + p * x[0]],
                       ["t", "x", "z", "p"], ["ode", "alg"])


@pytest.fixture
def builds(monkeypatch) -> list:
    return counted_builds(monkeypatch, library)


def test_values_and_jacobian_equal_sx_and_second_call_builds_nothing(toolchain, tmp_path,
                                                                     builds):
    f = _function()
    compiled = codegen.compile_functions({"f": f}, with_jacobian={"f"}, toolchain=toolchain,
                                         root=tmp_path)
    assert compiled["f"].class_name() == "External" and len(builds) == 1
    assert compiled["f"].name_in() == f.name_in() and compiled["f"].name_out() == f.name_out()
    x, y = ca.MX.sym("x", 3), ca.MX.sym("y")
    jacobians = [ca.Function("j", [x, y], [ca.jacobian(g(x, y)[0], ca.vertcat(x, y))])
                 for g in (compiled["f"], f)]
    assert "jac_f" in str(jacobians[0].find_functions())  # differentiated through the C
    for seed in range(3):
        args = np.random.default_rng(seed).uniform(-1, 1, 4)
        inputs = [args[:3], args[3]]
        for a, b in zip(compiled["f"](*inputs), f(*inputs), strict=True):
            # the same operations in C: the issue's compiled-vs-interpreted bound
            np.testing.assert_allclose(a.full(), b.full(), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(jacobians[0](*inputs).full(), jacobians[1](*inputs).full(),
                                   rtol=1e-12, atol=1e-12)  # the same bound
    again = codegen.compile_functions({"f": _function()}, with_jacobian={"f"},
                                      toolchain=toolchain, root=tmp_path)
    assert len(builds) == 1  # rebuilt from scratch, same content: the cached library
    np.testing.assert_array_equal(again["f"](args[:3], args[3])[0].full(),
                                  compiled["f"](args[:3], args[3])[0].full())
    codegen.compile_functions({"f": _function(3.0)}, toolchain=toolchain, root=tmp_path)
    assert len(builds) == 2  # another content: another library


def test_integrator_takes_daef_and_jacf_from_the_library(toolchain, tmp_path):
    residual = _oscillator()
    compiled = codegen.compile_functions({"f": _function(), "osc": residual},
                                         integrators={"osc"}, toolchain=toolchain,
                                         root=tmp_path)
    dae = compiled["osc"]
    assert dae.name_in() == ca.dyn_in() and dae.name_out() == ca.dyn_out()
    integrator = ca.integrator("i", "idas", dae, 0.0, [1.0], {"abstol": 1e-12, "reltol": 1e-12})
    assert integrator.get_function("jacF").class_name() == "External"
    out = integrator(x0=[1.0, 0.0], z0=-4.0, p=4.0)
    # x'' = -4 x from rest at 1: cos(2 t); IDAS at 1e-12 (measured error 2e-11)
    np.testing.assert_allclose(float(out["xf"][0]), np.cos(2.0), rtol=0, atol=1e-9)


def test_bad_names_are_refused(toolchain, tmp_path):
    with pytest.raises(ValueError, match="not among"):
        codegen.compile_functions({"f": _function()}, with_jacobian={"g"}, root=tmp_path)
    with pytest.raises(ValueError, match="DAE residual"):
        codegen.compile_functions({"f": _function()}, integrators={"f"}, root=tmp_path)


def _keyed(toolchain, root, content, calls: list, gain: float = 2.0) -> dict:
    """library.compile_keyed of f (compiled, with its Jacobian) and g (kept), counting make()."""
    def make():
        calls.append(content)
        x = ca.SX.sym("x", 2)
        kept = ca.Function("g", [x], [ca.exp(x[0]) * x[1]], ["x"], ["y"])
        return {"f": _function(gain)}, {"g": kept}, toolchain

    return library.compile_keyed(content, make, with_jacobian={"f"}, toolchain=toolchain,
                                 root=root)


def test_keyed_functions_build_once_per_content_and_keep_the_kept_serialized(toolchain,
                                                                            tmp_path):
    calls = []
    first = _keyed(toolchain, tmp_path, {"model": "a"}, calls)
    assert len(calls) == 1 and first["f"].class_name() == "External"
    assert first["g"].is_a("SXFunction")  # deserialized, evaluated interpreted
    inputs = [np.array([0.3, -0.7, 0.2]), 0.4]
    for a, b in zip(first["f"](*inputs), _function()(*inputs), strict=True):
        # the same operations in C: the compiled-vs-interpreted bound
        np.testing.assert_allclose(a.full(), b.full(), rtol=1e-12, atol=1e-12)
    # CasADi's serialization round trip keeps the graph: exactly the same value
    assert float(first["g"]([0.5, 2.0])) == np.exp(0.5) * 2.0
    again = _keyed(toolchain, tmp_path, {"model": "a"}, calls, gain=5.0)
    # the same content: the cached library, make() not called (the gain it would build with
    # is not the one in the library)
    assert len(calls) == 1
    np.testing.assert_array_equal(again["f"](*inputs)[0].full(), first["f"](*inputs)[0].full())
    other = _keyed(toolchain, tmp_path, {"model": "b"}, calls, gain=5.0)
    assert len(calls) == 2  # another content: another library, built by make()
    assert float(other["f"](*inputs)[0][0]) == pytest.approx(
        np.sin(0.3) * -0.7 + 5.0 * 0.4, rel=1e-12)  # the closed form of its f


def test_an_edited_kept_function_is_rebuilt(toolchain, tmp_path):
    """A kept function's file is checked like a library (codegen.trust: its sha256 in the
    manifest); an edited one makes the entry corrupt, which the cache builds again."""
    calls = []
    _keyed(toolchain, tmp_path, {"model": "a"}, calls)
    [kept] = list(tmp_path.glob("*/g.casadi"))
    kept.write_text(kept.read_text() + "0")  # (another size: trust rehashes it)
    with pytest.warns(UserWarning):  # the cache says it discards a corrupt entry
        functions = _keyed(toolchain, tmp_path, {"model": "a"}, calls)
    assert len(calls) == 2
    assert float(functions["g"]([0.5, 2.0])) == np.exp(0.5) * 2.0
