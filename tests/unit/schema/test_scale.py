"""Physical ranges (issue 35 item 12): masses, inertias and directions above floors set by the
model's own scale (schema/scale.py, E411/E404), stiffness and damping not negative unless the
element says `allow_negative: true` (E103). (A tsda whose points coincide: casmech check,
tests/integration/cli/test_check.py.)"""

import numpy as np
import pytest

import casmech
from casmech.errors import ModelError
from casmech.schema import load_model_text, scale

MODEL = """\
casmech: 1
name: pend
gravity: [0, 0, -9.81]
bodies:
  - {name: bar, mass: 1, inertia: [1, 1, 1], position: [0, 0, -1]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [1, 0, 0]}
forces:
  - {name: spring, type: tsda, body_i: ground, at_i: [0, 1, 0], body_j: bar, at_j: [0, 0, -1],
     stiffness: 10, damping: 1}
  - {name: twist, type: rsda, joint: pivot, stiffness: 5, damping: 0.5}
  - {name: mount, type: bushing, body_i: ground, body_j: bar, at: [0, 0, -1],
     stiffness: [1, 1, 1], damping: [1, 1, 1]}
analysis: {type: dynamics, t_end: 1, output_step: 0.01}
"""
LIGHT = ("  - {name: light, mass: MASS, inertia: [INERTIA, INERTIA, INERTIA], "
         "position: [0, 0, -2]}\n")


def findings(text: str) -> list[tuple[str, str, str]]:
    with pytest.raises(ModelError) as caught:
        load_model_text(text, "m.yaml")
    return [(d.code, d.path, d.message) for d in caught.value.diagnostics]


def with_light(mass: str, inertia: str = "1e-12") -> str:
    body = LIGHT.replace("MASS", mass).replace("INERTIA", inertia)
    return MODEL.replace("joints:\n", body + "joints:\n")


def test_the_model_is_fine():
    load_model_text(MODEL)
    load_model_text(with_light("1e-6", "1e-7"))  # a nearly massless link: 1e-6 of its neighbour


@pytest.mark.parametrize("mass", ["2e-320", "1e-300", "1e-16"])
def test_a_mechanism_lighter_than_the_least_mass_is_located(mass):
    text = MODEL.replace("mass: 1,", f"mass: {mass},").replace("inertia: [1, 1, 1]",
                                                                 "inertia: [1e-20, 1e-20, 1e-20]")
    [(code, path, message)] = findings(text)
    assert (code, path) == ("E411", "bodies[0].mass") and "least mass" in message


def test_a_body_far_lighter_than_the_heaviest_is_located():
    [(code, path, message)] = findings(with_light("1e-13", "1e-10"))
    assert (code, path) == ("E411", "bodies[1].mass")
    assert "heaviest body's (1 kg, 'bar')" in message
    # the floor is relative: the same ratio a billion times heavier is refused the same way
    heavy = with_light("1e-4", "1e-2").replace("mass: 1,", "mass: 1e9,")
    assert [f[:2] for f in findings(heavy)] == [("E411", "bodies[1].mass")]


@pytest.mark.parametrize("inertia", ["1e-300", "1e-16"])
def test_an_inertia_below_the_models_scale_is_located(inertia):
    text = MODEL.replace("inertia: [1, 1, 1]", f"inertia: [{inertia}, {inertia}, {inertia}]")
    [(code, path, message)] = findings(text)
    assert (code, path) == ("E411", "bodies[0].inertia") and "inertia scale" in message


def test_the_inertia_scale_is_the_heaviest_mass_times_the_length_scale_squared():
    text = with_light("1e-6", "1e-9")
    model = load_model_text(text)  # 1e-9 >= 1e-15 * 1 kg * (2 m)^2
    assert len(model.bodies) == 2
    check = scale.Scale()
    for body in model.bodies:
        check.add(body.name, body.mass, body.inertia, body.position)
    assert (check.heaviest, check.mass, check.length) == ("bar", 1.0, 2.0)
    assert findings(with_light("1e-6", "3e-15"))[0][:2] == ("E411", "bodies[1].inertia")


@pytest.mark.parametrize("old, new, path", [
    ("axis: [1, 0, 0]}", "axis: [1e-12, 0, 0]}", "joints[0].axis"),
    ("axis: [1, 0, 0]}", "axis: [1, 0, 0]}\n  - {name: c1, type: dp1, body_i: ground, "
     "a_i: [0, 0, 1e-12], body_j: bar, a_j: [1, 0, 0]}", "joints[1].a_i"),
    ("axis: [1, 0, 0]}", "axis: [1, 0, 0]}\n  - {name: c1, type: cd, c: [1e-4, 0, 0], "
     "body_i: ground, s_i: [0, 0, 0], body_j: bar, s_j: [0, 0, 1]}", "joints[1].c"),
])
def test_directions_of_no_sensible_length_are_located(old, new, path):
    found = findings(MODEL.replace(old, new))
    assert [f[:2] for f in found] == [("E404", path)] and "too short" in found[0][2]


def test_a_short_axis_is_fine_when_it_is_long_for_the_model():
    """An axis is normalised: a millimetre-long one in a one-metre model points well."""
    model = load_model_text(MODEL.replace("axis: [1, 0, 0]}", "axis: [1e-3, 0, 0]}"))
    np.testing.assert_allclose(model.joints[0].vectors["axis"], [1, 0, 0],
                               rtol=0, atol=1e-15)  # normalised exactly up to roundoff


@pytest.mark.parametrize("old, new, path, name", [
    ("stiffness: 10,", "stiffness: -10,", "forces[0].stiffness", "spring"),
    ("damping: 1}", "damping: -1}", "forces[0].damping", "spring"),
    ("stiffness: 10,", "stiffness: 10, free_length: -0.5,", "forces[0].free_length", "spring"),
    ("stiffness: 5,", "stiffness: -5,", "forces[1].stiffness", "twist"),
    ("damping: 0.5}", "damping: -0.5}", "forces[1].damping", "twist"),
    ("stiffness: [1, 1, 1]", "stiffness: [1, -1, 1]", "forces[2].stiffness", "mount"),
])
def test_negative_coefficients_need_allow_negative(old, new, path, name):
    text = MODEL.replace(old, new)
    found = findings(text)
    assert [f[:2] for f in found] == [("E103", path)] and "must not be negative" in found[0][2]
    load_model_text(text.replace(f"{{name: {name}, ", f"{{name: {name}, allow_negative: true, "))


UNSTABLE = """\
casmech: 1
name: unstable
gravity: [0, 0, 0]
bodies:
  - {name: slider, mass: 2, inertia: [1, 1, 1], position: [0.01, 0, 0]}
joints:
  - {name: rail, type: translational, body_i: ground, body_j: slider, at: [0, 0, 0],
     axis: [1, 0, 0]}
forces:
  - {name: push, type: tsda, body_i: ground, at_i: [-1, 0, 0], body_j: slider,
     at_j: [0.01, 0, 0], free_length: 1, stiffness: -8, allow_negative: true}
analysis: {type: dynamics, t_end: 1, output_step: 0.1, rtol: 1e-10, atol: 1e-12}
"""


def test_allow_negative_runs_the_negative_stiffness_it_allows():
    """x'' = (8 / 2) x from x = 0.01 at rest: x = 0.01 cosh(2 t), the closed form of a spring
    of negative stiffness (it pushes the slider away from its rest point)."""
    functions = casmech.compile(casmech.loads(UNSTABLE))
    result = casmech.analyze(functions)
    names, values = casmech.results_table(functions, result)
    t = values[:, 0]
    np.testing.assert_allclose(values[:, names.index("slider.x")], 0.01 * np.cosh(2 * t),
                               rtol=1e-7, atol=0)  # the integrator's rtol 1e-10, with margin
