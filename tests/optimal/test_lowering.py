"""dd/dtheta by central differences of the lowering, against closed forms of the pendulum's
initial pose (models/estimate_pendulum.yaml: position L/2 (0, sin a0, -cos a0), orientation
(cos a0/2, sin a0/2, 0, 0)) and against the symbolic re-lowering's exact mass and inertia."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.errors import UsageError
from casmech.optimal import lowering
from casmech.optimal.symbolic import symbolic_model
from tests.conftest import MODELS

PENDULUM = MODELS / "estimate_pendulum.yaml"


def _selected(derivative, expression) -> np.ndarray:
    """d expression / d theta for an expression of the split IR's symbols d."""
    symbols = derivative.split.symbols
    select = ca.Function("s", [symbols], [ca.jacobian(expression, symbols)])
    return np.array(select(derivative.split.values).full()) @ derivative.jacobian


def test_initial_pose_against_closed_forms():
    model = casmech.load(PENDULUM)
    derivative = lowering.derivative(model, ["L", "a0"])
    bar = derivative.split.ir.bodies[0]
    a0, length = model.parameters["a0"], model.parameters["L"]
    want_r0 = np.array([[0, 0], [np.sin(a0) / 2, length * np.cos(a0) / 2],
                        [-np.cos(a0) / 2, length * np.sin(a0) / 2]])
    want_p0 = np.array([[0, -np.sin(a0 / 2) / 2], [0, np.cos(a0 / 2) / 2], [0, 0], [0, 0]])
    # sixth-order differences at step 5e-3: measured 1.4e-14 against the closed forms
    np.testing.assert_allclose(_selected(derivative, bar.r0), want_r0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(_selected(derivative, bar.p0), want_p0, rtol=0, atol=1e-12)
    # the estimate covers the error (measured 3.5e-13 for both, mostly its round-off term)
    assert np.all(derivative.error < 1e-11)


def test_mass_and_inertia_against_the_symbolic_lowering():
    """A mass m exp(s) and an inertia Ic (1 + s^2): non-linear in s, exact through CasADi."""
    text = PENDULUM.read_text().replace("  Ic: 0.02", "  s: 0.3\n  Ic: 0.02").replace(
        "mass: m\n", "mass: m * exp(s)\n").replace(
        "inertia: [Ic, Ic, 1.0e-4]", "inertia: [Ic * (1 + s**2), Ic * (1 + s**2), 1.0e-4]")
    model = casmech.loads(text)
    derivative = lowering.derivative(model, ["s", "m"])
    exact = symbolic_model(model, ["s", "m"])
    bar, symbolic = derivative.split.ir.bodies[0], exact.ir.bodies[0]
    for got, want in ((bar.mass, symbolic.mass), (bar.inertia, symbolic.inertia)):
        jacobian = ca.Function("j", [exact.theta], [ca.jacobian(want, exact.theta)])
        # sixth-order differences of exp and a square: round-off (1e-12 relative bound)
        np.testing.assert_allclose(_selected(derivative, ca.vec(got)),
                                   np.array(jacobian(exact.values).full()), rtol=1e-12,
                                   atol=1e-14)


def test_overrides_are_kept():
    """Other parameters keep the values the model was loaded with (--set m=2, L=1.5)."""
    model = casmech.load(PENDULUM, {"m": "2", "L": "1.5"})
    derivative = lowering.derivative(model, ["a0"])
    assert 2.0 in derivative.split.values
    bar = derivative.split.ir.bodies[0]
    a0 = model.parameters["a0"]
    # d r0 / d a0 = L/2 (0, cos a0, sin a0) with the overridden L (round-off: measured 1e-15)
    np.testing.assert_allclose(_selected(derivative, bar.r0)[:, 0],
                               0.75 * np.array([0, np.cos(a0), np.sin(a0)]), rtol=0,
                               atol=1e-12)


def test_dependents_follow_expressions():
    model = casmech.load(MODELS / "four_bar.yaml")
    assert lowering.dependents(model, ["d"]) == {"d", "bo4", "beta", "alpha", "Cx", "Cy",
                                                 "phi3", "phi4"}
    assert lowering.dependents(model, ["m"]) == {"m"}


def test_structure_changes_are_located():
    model = casmech.load(PENDULUM, {"a0": "0"})
    line = 1 + model.text[:model.text.index("  a0:")].count("\n")
    with pytest.raises(UsageError, match=rf"estimate_pendulum.yaml:{line}:3: parameter 'a0' "
                                         r"changes the model's structure at a0 = .*'bar'.r0: 1 "
                                         "non-zero of 3 entries, now 2"):
        lowering.derivative(model, ["a0"])


def test_an_overridden_dependent_is_a_usage_error():
    """Cx is computed from d in four_bar.yaml; with Cx set on the command line, moving d
    cannot reproduce the model that was given."""
    model = casmech.load(MODELS / "four_bar.yaml", {"Cx": "1.7"})
    with pytest.raises(UsageError, match="four_bar.yaml:15:3: parameter 'd' cannot be moved "
                                         "alone.*Cx"):
        lowering.derivative(model, ["d"])


def test_a_kink_near_the_value_takes_a_smaller_step_or_is_refused():
    """mass 1 + |s - 0.5|: a kink at s = 0.5. At s = 0.501 the stencil at h = 1e-2 |s| crosses
    it, the estimate says so, and the step 1e-4 |s| does not: dm/ds = 1. At s = 0.50001 every
    step crosses it: a located usage error."""
    text = PENDULUM.read_text().replace("  Ic: 0.02", "  s: 0.501\n  Ic: 0.02").replace(
        "mass: m\n", "mass: 1 + abs(s - 0.5)\n")
    derivative = lowering.derivative(casmech.loads(text), ["s"])
    mass = derivative.split.ir.bodies[0].mass
    # piecewise linear: the small step is exact to round-off
    np.testing.assert_allclose(_selected(derivative, mass), [[1.0]], rtol=1e-10, atol=0)
    line = 1 + text[:text.index("  s: 0.501")].count("\n")
    with pytest.raises(UsageError, match=rf"<string>:{line}:3: parameter 's' moves the model's "
                                         "numbers non-smoothly"):
        lowering.derivative(casmech.loads(text.replace("s: 0.501", "s: 0.50001")), ["s"])
