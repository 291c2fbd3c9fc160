"""Units in expressions (docs/format.md#units): numbers with units converted to SI by the
units' definitions (NIST SP 811: the inch 0.0254 m, the pound 0.45359237 kg and standard
gravity 9.80665 m/s^2 exactly), each field's dimension enforced (E205), units through
parameters, `--set` and symbolic parameters. That every model without units reads as before is
tests/unit/model/test_plain_lowering.py's: the lowering of every gallery model is bit for bit
the one recorded before units existed."""

import math
import subprocess
import sys

import numpy as np
import pytest

import casmech
from casmech.core import units
from casmech.core.expressions import ExpressionSyntaxError, parse
from casmech.errors import ModelError
from casmech.optimal.sensitivity import sensitivity
from tests.conftest import MODELS, Table


@pytest.mark.parametrize(("text", "si"), [
    ("30 deg", 30 * math.pi / 180), ("1000 mm", 1.0), ("2 kN", 2000.0), ("1.5 t", 1500.0),
    ("3000 rpm", 3000 * 2 * math.pi / 60), ("2 in", 2 * 0.0254), ("3 lb", 3 * 0.45359237),
    ("1 lbf", 0.45359237 * 9.80665), ("2 kN*m", 2000.0), ("50 N/mm", 50e3),
    ("9.81 m/s**2", 9.81), ("1 m*s**-2", 1.0), ("1 rev", 2 * math.pi), ("2 h", 7200.0),
    ("5 N*m/deg", 5 * 180 / math.pi), ("7.8 g/cm**3", 7800.0), ("1 GPa", 1e9),
])
def test_numbers_with_units_are_their_si_values(text, si):
    np.testing.assert_allclose(parse(text).evaluate({}), si, rtol=1e-15,
                               atol=0)  # one or two roundings of the factors
    assert parse(text).root.length == len(text)


def test_a_unit_is_written_without_spaces_and_t_only_after_its_number():
    product = parse("2 kN * m")  # 2 kN times the name m
    assert product.symbols == {"m"} and product.evaluate({"m": 3.0}) == 6000.0
    speed = parse("0.1 m/s*t")  # a speed times the time
    assert speed.symbols == {"t"} and speed.evaluate({"t": 2.0}) == pytest.approx(0.2, abs=0)


@pytest.mark.parametrize(("text", "message", "offset"), [
    ("30 degree", "unknown unit 'degree'", 3),
    ("2 m**x", "a unit's power is an integer", 3),
])
def test_bad_units_are_syntax_errors_at_their_place(text, message, offset):
    with pytest.raises(ExpressionSyntaxError) as caught:
        parse(text)
    assert (caught.value.message, caught.value.offset) == (message, offset)


def test_90_deg_and_pi_over_2_give_identical_results():
    """The double pendulum released from theta1 = 90 deg and from pi/2: the same table, bit
    for bit."""
    text = (MODELS / "double_pendulum.yaml").read_text()
    assert "theta1: pi/2" in text
    tables = []
    for written in ("pi/2", "90 deg"):
        model = casmech.loads(text.replace("theta1: pi/2", f"theta1: {written}"))
        functions = casmech.compile(model)
        result = casmech.analyze(functions, t_end=0.5)
        tables.append(casmech.results_table(functions, result)[1])
    assert np.array_equal(tables[0], tables[1])


BAR = """\
casmech: 1
name: bar
parameters:
  L: 2000 mm
  m: 3 kg
bodies:
  - {name: bar, mass: %s, inertia: [0.01, 1, 1], position: [L/2, 0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 0, 1]%s}
forces:
  - {name: spring, type: rsda, joint: pivot, stiffness: %s}
analysis: {type: dynamics, t_end: 0.2}
"""


def bar(mass: str = "m", joint: str = "", stiffness: str = "5 N*m/rad") -> str:
    return BAR % (mass, joint, stiffness)


@pytest.mark.parametrize(("mass", "joint", "stiffness", "path", "expected", "got"), [
    ("15 mm", "", "5 N*m/rad", "bodies[0].mass", "mass (kg)", "15 mm"),
    ("L", "", "5 N*m/rad", "bodies[0].mass", "mass (kg)", "L"),
    ("m", ", initial: {angle: 2 m}", "5 N*m/rad", "joints[0].initial.angle",
     "number (an angle in rad)", "2 m"),
    ("m", ", initial: {angle_dot: 3 m/s}", "5 N*m/rad", "joints[0].initial.angle_dot",
     "angular velocity or frequency (rad/s)", "3 m/s"),
    ("m", "", "5 N/m", "forces[0].stiffness", "torque or energy (N m)", "5 N/m"),
])
def test_a_value_of_the_wrong_dimension_names_the_expected_one(mass, joint, stiffness, path,
                                                               expected, got):
    with pytest.raises(ModelError) as caught:
        casmech.loads(bar(mass, joint, stiffness))
    [found] = caught.value.diagnostics
    assert (found.code, found.path, found.expected, found.got) == ("E205", path, expected, got)
    assert found.message == f"expected a {expected}, got a " + found.message.split(", got a ")[1]


@pytest.mark.parametrize(("mass", "message", "at"), [
    ("m + L", "'+' of different dimensions: mass (kg) and length (m)", "+"),
    ("m * sin(L)", "sin() of a length (m): its argument must be a number (an angle in rad)",
     "sin"),
    ("m * 2 ** L", "an exponent must be a number, not a length (m)", "**"),
])
def test_dimensions_that_disagree_inside_an_expression(mass, message, at):
    text = bar(mass)
    with pytest.raises(ModelError) as caught:
        casmech.loads(text)
    [found] = caught.value.diagnostics
    assert (found.code, found.path, found.message) == ("E205", "bodies[0].mass", message)
    line = text.splitlines()[6]
    assert (found.source.line, found.source.col) == (7, line.index(at) + 1)  # at the operator


def test_units_reach_the_lowered_model_in_si():
    model = casmech.loads(bar(joint=", initial: {angle: 30 deg, angle_dot: 60 rpm}"))
    assert model.parameters["L"] == 2.0 and model.parameters["m"] == 3.0
    np.testing.assert_allclose(model.bodies[0].position, [1.0, 0, 0], rtol=0, atol=0)
    functions = casmech.compile(model)
    table = Table(*casmech.results_table(functions, casmech.analyze(functions, "assembly")))
    np.testing.assert_allclose(table["pivot.angle"][0], math.pi / 6, rtol=0, atol=1e-15)
    np.testing.assert_allclose(table["pivot.angle_dot"][0], 2 * math.pi, rtol=0, atol=1e-14)


def test_set_takes_units_and_plain_si_alike():
    with_units = casmech.loads(bar(), overrides={"L": "1500 mm"})
    plain = casmech.loads(bar(), overrides={"L": "1.5"})
    assert with_units.parameters["L"] == plain.parameters["L"] == 1.5


def test_symbolic_parameters_written_with_units_differentiate_in_si():
    """d(bar.x)/dL of the swinging bar with L written in mm: the exact derivative is per
    metre (SI), as a central difference of two runs with L set in metres shows."""
    model = casmech.loads(bar())
    found = sensitivity(model, ["L"], ["bar.x"], [0.2])
    assert found.values.shape == (1, 1)
    runs = []
    for value in ("2.000001", "1.999999"):
        functions = casmech.compile(casmech.loads(bar(), overrides={"L": value}))
        table = Table(*casmech.results_table(functions, casmech.analyze(
            functions, rtol=1e-12, atol=1e-14)))
        runs.append(table["bar.x"][-1])
    np.testing.assert_allclose(found.jacobian[0, 0, 0], (runs[0] - runs[1]) / 2e-6, rtol=1e-5,
                               atol=0)  # central difference error O(h^2) + integration 1e-10


SLIDER = """\
casmech: 1
name: slider
bodies:
  - {name: block, mass: 2, inertia: [1, 1, 1], position: [0, 0, 0]}
joints:
  - {name: slide, type: translational, body_i: ground, body_j: block, at: [0, 0, 0],
     axis: [1, 0, 0], friction: %s}
analysis: {type: dynamics, t_end: 0.2}
"""


@pytest.mark.parametrize(("text", "friction", "si"), [
    (BAR % ("m", ", friction: %s", "0"), "{coulomb: 2 N*m, static: 3 N*m, "
     "viscous: 0.5 N*m*s/rad}", (2.0, 3.0, 0.5)),
    (BAR % ("m", ", friction: %s", "0"), "{coulomb: 2000 N*mm, viscous: 0.5 N*m*s}",
     (2.0, None, 0.5)),
    (SLIDER, "{coulomb: 2 kN, static: 3 kN, viscous: 0.5 N*s/m}", (2000.0, 3000.0, 0.5)),
])
def test_joint_friction_takes_the_units_of_its_coordinate(text, friction, si):
    written = casmech.loads(text % friction).joints[0].friction
    coulomb, static, viscous = si
    # the SI value of a unit conversion, to the last bit of its factor
    np.testing.assert_allclose([written["coulomb"], written["static"], written["viscous"]],
                               [coulomb, coulomb if static is None else static, viscous],
                               rtol=1e-15, atol=0)


@pytest.mark.parametrize(("text", "friction", "path", "expected"), [
    (BAR % ("m", ", friction: %s", "0"), "{coulomb: 2 kN}", "joints[0].friction.coulomb",
     "torque or energy (N m)"),
    (BAR % ("m", ", friction: %s", "0"), "{coulomb: 1 N*m, static: 2 N}",
     "joints[0].friction.static", "torque or energy (N m)"),
    (BAR % ("m", ", friction: %s", "0"), "{viscous: 2 N*s/m}", "joints[0].friction.viscous",
     None),
    (SLIDER, "{coulomb: 2 N*m}", "joints[0].friction.coulomb", "force (N)"),
    (SLIDER, "{viscous: 2 N*m*s}", "joints[0].friction.viscous", None),
])
def test_joint_friction_of_the_wrong_dimension_is_located(text, friction, path, expected):
    text = text % friction
    with pytest.raises(ModelError) as caught:
        casmech.loads(text, "m.yaml")
    [found] = caught.value.diagnostics
    assert (found.code, found.path) == ("E205", path)
    if expected is not None:
        assert found.expected == expected
    key = path.rpartition(".")[2]
    line = next(n for n, row in enumerate(text.splitlines(), 1) if "friction:" in row)
    row = text.splitlines()[line - 1]
    # at the value
    assert (found.source.line, found.source.col) == (line, row.index(f"{key}: ") + len(key) + 3)


def test_an_instance_position_and_a_free_final_time_take_their_dimensions():
    from tests.integration.optimal.test_blocks import BASE
    from tests.unit.schema.test_components import rig

    placed = rig((0, 0, -9.81))
    ocp = BASE + ("\nocp:\n  horizon: 2\n  free_time: %s\n  objective: {effort: 0.1, time: 1}\n"
                  "  controls: [{joint: pivot}]\n")
    in_mm = casmech.loads(placed.replace("position: [0, 0, 0]", "position: [500 mm, 0, 0]"))
    in_m = casmech.loads(placed.replace("position: [0, 0, 0]", "position: [0.5, 0, 0]"))
    # a unit conversion: the same SI numbers to the last bit of its factor
    np.testing.assert_allclose(in_mm.bodies[0].position, in_m.bodies[0].position, rtol=1e-15,
                               atol=0)
    assert casmech.loads(ocp % "[500 ms, 3 s]").ocp.free_time == (0.5, 3.0)
    for text, path in ((placed.replace("position: [0, 0, 0]", "position: [2 kg, 0, 0]"),
                        "instances[0].position[0]"), (ocp % "[0.5 kg, 3]", "ocp.free_time[0]")):
        with pytest.raises(ModelError) as caught:
            casmech.loads(text)
        assert [(d.code, d.path) for d in caught.value.diagnostics] == [("E205", path)]


def test_dimensions_from_powers_find_their_names():
    """A dimension is ints, a power's Fractions where it makes them: equal, and named, alike."""
    area = units.dimension(length=2)
    assert units.power(area, 0.5) == units.LENGTH
    assert units.describe(units.power(area, 0.5)) == "length (m)"
    assert units.describe(units.power(units.LENGTH, 0.5)) == "m^1/2"
    assert units.describe(units.multiply(units.FORCE, units.LENGTH)) == "torque or energy (N m)"


def test_reading_units_imports_no_fractions():
    """fractions (and decimal) are imported for a power of a unit only, not to read a model."""
    code = ("import sys; import casmech.core.expressions, casmech.elements.coordinate_kinds, "
            "casmech.elements.couplings; print('fractions' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=True)
    assert done.stdout.strip() == "False"
