"""Adding a joint type is one registry entry (casmech.elements.joint_types; docs/architecture.md).

A test-only type, `point_on_line` (body j's point `at` stays on the line through `at` along
`axis` carried by body i: 4 DOF, two DP2 rows; it slides along the axis and turns freely),
is registered by a fixture and removed after. A model using it loads, is checked, runs
dynamics in the r-p DAE and in joint coordinates (its tree motion), and gives the motion and
reaction of the same mechanism written with two basic DP2 constraints (a second formulation).
"""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.core.quaternions import from_matrix, unit
from casmech.elements import joint_types
from casmech.elements.joint_types import ON_AXIS, JointType
from casmech.elements.motions import Motion
from casmech.errors import ModelError
from casmech.schema import export
from casmech.schema.bodies import rotation_matrix
from tests.conftest import Table

POINT_ON_LINE = JointType(
    "point_on_line", ("at", "axis"), ON_AXIS, coordinates=("displacement",),
    limit="displacement",
    motion=Motion(5, 4, lambda th: unit(th[0:4]), lambda th: ca.vertcat(0, 0, th[4]),
                  lambda r, d: np.concatenate([from_matrix(r), [d[2]]]), quaternions=(0,),
                  drivers={"displacement": 4}))

AT, AXIS = np.array([0.2, -0.1, 1.0]), np.array([1.0, 0.5, -0.4]) / np.linalg.norm([1, 0.5, -0.4])


def vec(v) -> str:
    return "[" + ", ".join(repr(float(x)) for x in v) + "]"


BOB = np.array([0.5, 0.3, 0.6])  # the CM, away from the joint point
HEADER = f"""
casmech: 1
name: bead
bodies:
  - {{name: bob, mass: 2, inertia: [0.3, 0.2, 0.1], position: {vec(BOB)},
     orientation: {{axis_angle: {{axis: [1, 2, 3], angle: 0.4}}}},
     velocity: [0.3, 0.1, -0.2], angular_velocity: [1.0, -0.5, 2.0]}}
"""
ANALYSIS = "analysis: {type: dynamics, t_end: 0.6, output_step: 0.05, rtol: 1e-10, atol: 1e-12}\n"
POSITION = ("x", "y", "z", "e0", "e1", "e2", "e3")



def toy_model(extra: str = "") -> str:
    return HEADER + f"""joints:
  - {{name: slide, type: point_on_line, body_i: ground, body_j: bob, at: {vec(AT)},
     axis: {vec(AXIS)}{extra}}}
""" + ANALYSIS


def basic_model() -> str:
    """The same joint as two DP2 rows: u_i . d_ij = 0, v_i . d_ij = 0 (body frames)."""
    rotation = casmech.loads(HEADER + ANALYSIS).bodies[0].euler_parameters
    s_j = rotation_matrix(rotation).T @ (AT - BOB)  # the joint point in bob's frame
    u = np.cross(AXIS, [0, 0, 1.0])
    u /= np.linalg.norm(u)
    rows = "".join(
        f"  - {{name: {name}, type: dp2, body_i: ground, body_j: bob, a_i: {vec(a)}, "
        f"s_i: {vec(AT)}, s_j: {vec(s_j)}}}\n"
        for name, a in (("across", u), ("normal", np.cross(AXIS, u))))
    return HEADER + "joints:\n" + rows + ANALYSIS


@pytest.fixture
def point_on_line():
    joint_types.register(POINT_ON_LINE)
    yield POINT_ON_LINE
    joint_types.unregister(POINT_ON_LINE.name)


def run(text: str, formulation: str) -> Table:
    functions = casmech.compile(casmech.loads(text))
    return Table(*casmech.results_table(functions, casmech.analyze(
        functions, formulation=formulation)))


@pytest.mark.parametrize("formulation", ["rp", "joint"])
def test_a_registered_joint_type_runs_like_its_basic_constraints(point_on_line, formulation):
    toy, basic = run(toy_model(), formulation), run(basic_model(), "rp")
    for column in POSITION:
        # two integrations at rtol 1e-10 of the same motion over 0.6 s: global errors of
        # ~1e-9 (as tests/validation/runtime/test_joint_dynamics.py measures for its trees)
        np.testing.assert_allclose(toy[f"bob.{column}"], basic[f"bob.{column}"], rtol=0,
                                   atol=1e-7, err_msg=column)
    for axis in "xyz":
        # the joint's reaction force is the two rows' together (both taken at the joint
        # point); algebraic in the state, so it carries the error amplified (tolerance 1e-6)
        together = basic[f"across.f{axis}"] + basic[f"normal.f{axis}"]
        np.testing.assert_allclose(toy[f"slide.f{axis}"], together, rtol=0, atol=1e-6)
    # the point stays on the line: the coordinate a force law reads is the slide along it
    assert np.max(toy["constraint_violation"]) < 1e-8


def test_its_displacement_is_what_a_motor_acts_along(point_on_line):
    """The entry's coordinate: an effort motor along the slide written as a spring,
    f = -k s, with gravity off. The motor has no potential in `energy` (kinetic only here), so
    kinetic + 1/2 k s^2, s the slide of the joint point along the axis, stays constant."""
    k = 50.0
    text = toy_model(f", motor: {{force: -{k} * displacement}}").replace(
        "casmech: 1\n", "casmech: 1\ngravity: [0, 0, 0]\n")
    table = run(text, "rp")
    p0 = casmech.loads(text).bodies[0].euler_parameters
    s_bar = rotation_matrix(p0).T @ (AT - BOB)  # the joint point in bob's frame
    points = [np.array([table["bob.x"][n], table["bob.y"][n], table["bob.z"][n]])
              + rotation_matrix([table[f"bob.e{m}"][n] for m in range(4)]) @ s_bar
              for n in range(len(table["t"]))]
    s = (np.array(points) - AT) @ AXIS
    total = table["energy"] + 0.5 * k * s**2
    assert s.min() < -1e-2 and s.max() > 1e-2  # the spring swings it both ways
    # conserved to the integrator's rtol 1e-10 over 0.6 s (scale ~1 J: atol 1e-7)
    np.testing.assert_allclose(total, total[0], rtol=0, atol=1e-7)


def test_the_schema_checks_come_from_the_entry(point_on_line):
    """Drivers, rsda and motors the entry does not list are refused with the entry's facts."""
    with pytest.raises(ModelError) as angle:
        casmech.loads(toy_model(", driver: {angle: t}"))
    assert [d.code for d in angle.value.diagnostics] == ["E408"]
    assert "allowed on revolute, cylindrical and screw joints" in angle.value.diagnostics[0].hint
    with pytest.raises(ModelError) as motor:
        casmech.loads(toy_model(", motor: {torque: 1}"))
    assert "point_on_line joint's motor takes displacement | velocity | force" in \
        motor.value.diagnostics[0].hint
    driven = casmech.loads(toy_model(", driver: {displacement: 0.1 * t}"))
    assert driven.joints[0].drivers["displacement"] is not None


def test_unregistered_the_type_is_unknown_again(point_on_line):
    """Registering changes the format (the JSON Schema names the type); unregistering
    restores it exactly."""
    assert '"point_on_line"' in export.schema_text()
    joint_types.unregister(POINT_ON_LINE.name)
    try:
        with pytest.raises(ModelError) as found:
            casmech.loads(toy_model())
        assert found.value.diagnostics[0].path.startswith("joints[0]")
        assert export.schema_text() == export.DEFAULT_PATH.read_text(encoding="utf-8")
    finally:
        joint_types.register(POINT_ON_LINE)
