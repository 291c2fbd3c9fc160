"""Loading with symbolic parameters (schema.load_model's `symbolic`): which parameters are
traced numbers, what carries their expressions, and the located errors for names that are not
parameters and for parameters that set a count."""

import casadi as ca
import numpy as np
import pytest

from casmech.core import traced
from casmech.errors import ModelError
from casmech.schema import load_model, load_model_text
from tests.conftest import MODELS

CHAIN = MODELS / "chain_repeat.yaml"


def _codes(error: ModelError) -> list[tuple[str, str, int]]:
    return [(d.code, d.path, d.source.line if d.source else 0) for d in error.diagnostics]


def test_what_carries_the_expressions():
    """Parameters computed from a symbolic one, and what they set, are traced; the others are
    plain floats; the symbols and the overrides are recorded."""
    model = load_model(MODELS / "four_bar.yaml", {"m": "1.5"}, symbolic=["d"])
    assert model.overrides == {"m": "1.5"} and set(model.symbols) == {"d"}
    assert isinstance(model.symbols["d"], ca.SX)
    assert traced.is_traced(model.parameters["Cx"])  # computed from d
    assert not traced.is_traced(model.parameters["a"]) and model.parameters["m"] == 1.5
    rocker = next(b for b in model.bodies if b.name == "rocker")
    assert traced.is_traced(rocker.position) and traced.is_traced(rocker.euler_parameters)
    crank = next(b for b in model.bodies if b.name == "crank")
    assert crank.position.dtype == float  # d does not reach it
    plain = load_model(MODELS / "four_bar.yaml", {"m": "1.5"})
    # the values are the plain load's (the same float operations)
    np.testing.assert_array_equal(traced.value(rocker.position),
                                  next(b for b in plain.bodies if b.name == "rocker").position)


def test_an_instance_parameter_and_its_placement():
    """`front_left.L1` (a component's parameter in one instance) and the parent's `a` (an
    instance's position): only that instance's members move with L1."""
    model = load_model(MODELS / "quadruped_legs.yaml", symbolic=["front_left.L1", "a"])
    moved = {b.name for b in model.bodies if traced.is_traced(b.position)}
    assert "front_left.shank" in moved and "hind_right.shank" in moved  # a moves every hip
    only_l1 = load_model(MODELS / "quadruped_legs.yaml", symbolic=["front_left.L1"])
    assert {b.name for b in only_l1.bodies if traced.is_traced(b.position)} == {
        "front_left.thigh", "front_left.shank"}


def test_names_that_are_not_parameters():
    with pytest.raises(ModelError) as error:
        load_model(MODELS / "four_bar.yaml", symbolic=["dd"])
    assert ("E300", "symbolic dd", 0) in _codes(error.value)
    assert "did you mean 'd'" in str(error.value)
    with pytest.raises(ModelError) as error:
        load_model(MODELS / "quadruped_legs.yaml", symbolic=["front_lft.L1"])
    assert ("E300", "symbolic front_lft.L1", 0) in _codes(error.value)


def test_a_count_cannot_be_symbolic():
    """A repeat bound and a `{expr}` name read N: structure, an error at each (E103)."""
    text = CHAIN.read_text()
    with pytest.raises(ModelError) as error:
        load_model(CHAIN, symbolic=["N"])
    line = 1 + text[:text.index("repeat: {index: i, from: 1, to: N}")].count("\n")
    assert ("E103", "instances[0].repeat.to", line) in _codes(error.value)
    assert "cannot depend on a symbolic parameter (N)" in str(error.value)
    named = text.replace("body_j: link1.bar", 'body_j: "link{N - 3}.bar"')
    with pytest.raises(ModelError) as error:
        load_model_text(named, str(CHAIN), symbolic=["N"])
    line = 1 + text[:text.index("body_j: link1.bar")].count("\n")
    assert ("E103", "joints[0].body_j", line) in _codes(error.value)


def test_without_symbolic_no_traced_number():
    model = load_model(CHAIN)
    assert model.symbols == {} and model.overrides == {}
    assert all(b.position.dtype == float for b in model.bodies)
    assert not any(isinstance(v, traced.Traced) for v in model.parameters.values())


def test_functions_of_the_expression_language():
    """step, max and abs of a symbolic parameter: the mass 1 + step(s, 0, 0, 1, 2) +
    max(s, 0.1) + abs(s - 1) at s = 0.3 has d/ds = 2 * 6 s (1 - s) + 1 - 1 (closed form)."""
    text = (MODELS / "estimate_pendulum.yaml").read_text().replace(
        "  Ic: 0.02", "  Ic: 0.02\n  s: 0.3").replace(
        "mass: m\n", "mass: 1 + step(s, 0, 0, 1, 2) + max(s, 0.1) + abs(s - 1)\n")
    model = load_model_text(text, symbolic=["s"])
    mass = model.bodies[0].mass
    plain = load_model_text(text).bodies[0].mass
    assert traced.value(mass) == plain  # the float path's value
    symbol = model.symbols["s"]
    slope = float(ca.Function("d", [symbol], [ca.jacobian(mass.expr, symbol)])(0.3))
    # the closed form; round-off
    np.testing.assert_allclose(slope, 12 * 0.3 * 0.7, rtol=1e-14, atol=0)
