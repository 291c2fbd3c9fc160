"""Adding a coordinate kind is one registry entry (casmech.elements.coordinate_kinds;
docs/architecture.md, "Adding a coordinate kind").

A test-only kind, `lateral` (the slide of body j's joint point along the joint frame's u axis
carried by body i, where a displacement slides along the axis w), and a test-only joint type
using it, `lateral_slider` (rotation locked, the joint point on the line through `at` along u:
1 DOF), are registered by a fixture and removed after. A model using them loads with the
kind's driver, motor, stop, `initial:` and state names, and gives the motion, the coordinate
columns, the stop's force and the reaction of the same mechanism written with a translational
joint whose axis is that u (a second formulation); its driver removes its one DOF.
"""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.core.quaternions import IDENTITY
from casmech.core.states import JOINT_COORDINATES
from casmech.elements import coordinate_kinds, joint_types, primitives
from casmech.elements.coordinate_kinds import DISTANCE, CoordinateKind, slide_value
from casmech.elements.joint_types import NO_SPIN, PARALLEL, JointType
from casmech.elements.motions import Motion
from casmech.errors import ModelError
from casmech.model.lower import perpendicular_pair
from casmech.schema import export
from casmech.schema.bodies import rotation_matrix
from tests.conftest import Table

LATERAL = CoordinateKind(
    "lateral", slide_value, {"u_i": "u@i", "s_i": "P@i", "s_j": "P@j"},
    ("dp2", {"a_i": "u@i", "s_i": "P@i", "s_j": "P@j"}, "lateral slide = f(t)"),
    ("lateral", "lateral_speed", "lateral_force"), DISTANCE, "l",
    (("joint lateral slide", "lateral slides"), ("joint lateral velocity", "lateral velocities")),
    lambda frame, s: (None, s * frame("u")))
SLIDER = JointType(
    "lateral_slider", ("at", "axis"),
    PARALLEL + NO_SPIN + (
        ("dp2", {"a_i": "v@i", "s_i": "P@i", "s_j": "P@j"}, "v_i . d_ij = 0"),
        ("dp2", {"a_i": "w@i", "s_i": "P@i", "s_j": "P@j"}, "w_i . d_ij = 0")),
    coordinates=("lateral",), limit="lateral",
    motion=Motion(1, 1, lambda th: IDENTITY, lambda th: ca.vertcat(th[0], 0, 0),
                  lambda r, d: np.array([d[0]]), drivers={"lateral": 0}))  # along F_p's x: u

AT = np.array([0.2, -0.1, 1.0])
AXIS = np.array([1.0, 0.5, -0.4]) / np.linalg.norm([1, 0.5, -0.4])
U = perpendicular_pair(AXIS)[0]  # the joint frame's u: the toy's line, the rail's axis


def vec(v) -> str:
    return "[" + ", ".join(repr(float(x)) for x in v) + "]"


HEADER = """
casmech: 1
name: lateral
bodies:
  - {name: bob, mass: 2, inertia: [0.3, 0.2, 0.1], position: [0.5, 0.3, 0.6],
     orientation: {axis_angle: {axis: [1, 2, 3], angle: 0.4}}}
"""
ANALYSIS = "analysis: {type: dynamics, t_end: 0.6, output_step: 0.05, rtol: 1e-10, atol: 1e-12}\n"
POSITION = ("x", "y", "z", "e0", "e1", "e2", "e3")


def model(kind: str, extra: str, force: str = "") -> str:
    """The toy joint (`kind` "lateral") or a translational joint along U ("displacement"),
    named `slide`, with `extra` keys, and `force` as a force element's z value."""
    joint = (f"type: lateral_slider, at: {vec(AT)}, axis: {vec(AXIS)}" if kind == "lateral"
             else f"type: translational, at: {vec(AT)}, axis: {vec(U)}")
    forces = "" if not force else (
        f"forces:\n  - {{name: drag, type: force, body: bob, at: [0.5, 0.3, 0.6], "
        f"value: [0, 0, '{force}']}}\n")
    return (HEADER + f"joints:\n  - {{name: slide, body_i: ground, body_j: bob, {joint}"
            f"{extra}}}\n" + forces + ANALYSIS)


@pytest.fixture
def lateral():
    coordinate_kinds.register(LATERAL)
    joint_types.register(SLIDER)
    yield LATERAL
    joint_types.unregister(SLIDER.name)
    coordinate_kinds.unregister(LATERAL.name)


def run(text: str, formulation: str = "rp") -> Table:
    functions = casmech.compile(casmech.loads(text))
    return Table(*casmech.results_table(functions, casmech.analyze(
        functions, formulation=formulation)))


def same(kind: str, text: str) -> str:
    """The keys of the toy model written for the translational joint."""
    return text if kind == "lateral" else text.replace("lateral_force", "force").replace(
        "lateral", "displacement")


@pytest.mark.parametrize("formulation", ["rp", "joint"])
def test_a_registered_kind_runs_like_the_translational_joint(lateral, formulation):
    """Motor law, stop, friction, `initial:` and a force law read the toy's coordinate as the
    translational joint's along the same line: the same motion, coordinate, stop force and
    reaction."""
    extra = (", motor: {lateral_force: '-20*lateral - 0.3*lateral_dot + 2*sin(3*t)'}, "
             "limit: {lower: -0.04, upper: 0.06, stiffness: 2e4, damping: 5}, "
             "friction: {coulomb: 0.8, viscous: 0.5}, "
             "initial: {lateral: 0.01, lateral_dot: 0.4}")
    force = "-1.5*slide.lateral_dot"
    tables = {kind: run(model(kind, same(kind, extra), same(kind, force)), formulation)
              for kind in ("lateral", "displacement")}
    toy, rail = tables["lateral"], tables["displacement"]
    for column in POSITION:
        # two integrations at rtol 1e-10 of the same motion over 0.6 s through stop contacts:
        # global errors ~1e-9 of the stop's stiff law (tolerance 1e-7)
        np.testing.assert_allclose(toy[f"bob.{column}"], rail[f"bob.{column}"], rtol=0,
                                   atol=1e-7, err_msg=column)
    for toy_column, rail_column in (("lateral", "displacement"),
                                    ("lateral_dot", "displacement_dot"),
                                    ("limit_lateral_force", "limit_force"),
                                    ("limit_gap", "limit_gap"), ("friction", "friction"),
                                    ("friction_mode", "friction_mode")):
        # the same state's coordinate; a stop force of stiffness 2e4 amplifies 1e-9 (1e-4 N)
        np.testing.assert_allclose(toy[f"slide.{toy_column}"], rail[f"slide.{rail_column}"],
                                   rtol=0, atol=1e-4, err_msg=toy_column)
    assert np.max(np.abs(toy["slide.limit_lateral_force"])) > 1.0  # the stop was hit
    assert np.max(np.abs(toy["slide.friction"])) >= 0.8  # and the friction slid
    for axis in ("fx", "fy", "fz", "tx", "ty", "tz"):
        # the whole constraint wrench on bob at the joint point (motor and stop included), of
        # different rows; algebraic, with the stop's stiffness: tolerance 1e-3 N (N m)
        np.testing.assert_allclose(toy[f"slide.{axis}"], rail[f"slide.{axis}"], rtol=0,
                                   atol=1e-3, err_msg=axis)
    # the coordinate is the slide of the joint point along U (closed form from the poses)
    start = casmech.loads(model("lateral", extra)).bodies[0]
    s_bar = rotation_matrix(start.euler_parameters).T @ (AT - start.position)
    points = [np.array([toy["bob.x"][n], toy["bob.y"][n], toy["bob.z"][n]])
              + rotation_matrix([toy[f"bob.e{m}"][n] for m in range(4)]) @ s_bar
              for n in range(len(toy["t"]))]
    # the joint point's position from the pose columns: rounding of 1e-16 times ~1 m
    np.testing.assert_allclose((np.array(points) - AT) @ U, toy["slide.lateral"], rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(toy["slide.lateral"][0], 0.01, rtol=0, atol=1e-12)  # initial:


def test_its_driver_removes_its_one_dof(lateral):
    """`driver: {lateral: f(t)}` prescribes the slide (f at every output time) and removes
    the joint's one DOF, as a displacement driver of the translational joint does."""
    free = casmech.compile(casmech.loads(model("lateral", "")))
    rail = casmech.compile(casmech.loads(model("displacement", "")))
    assert free.dof == rail.dof == 1
    text = model("lateral", ", driver: {lateral: 0.05*sin(2*t)}").replace(
        "type: dynamics", "type: kinematics")
    driven = casmech.compile(casmech.loads(text))
    assert driven.dof == 0
    table = Table(*casmech.results_table(driven, casmech.analyze(driven)))
    # kinematics solved to its Newton tolerance (1e-10 and below)
    np.testing.assert_allclose(table["slide.lateral"], 0.05 * np.sin(2 * table["t"]), rtol=0,
                               atol=1e-9)
    speed = model("lateral", ", motor: {lateral_speed: 0.1*cos(2*t)}").replace(
        "type: dynamics", "type: kinematics")
    table = run(speed)
    # the speed mode's driver is the closed-form integral 0.05 sin(2t)
    np.testing.assert_allclose(table["slide.lateral"], 0.05 * np.sin(2 * table["t"]), rtol=0,
                               atol=1e-9)


def test_its_keys_are_checked_from_the_entry(lateral):
    """The kind's driver is refused on a joint type without it; its driver takes a length."""
    revolute = HEADER + (f"joints:\n  - {{name: pin, type: revolute, body_i: ground, "
                         f"body_j: bob, at: {vec(AT)}, axis: {vec(AXIS)}, "
                         "driver: {lateral: t}}\n") + ANALYSIS
    with pytest.raises(ModelError) as found:
        casmech.loads(revolute)
    assert [d.code for d in found.value.diagnostics] == ["E408"]
    assert "allowed on lateral_slider joints" in found.value.diagnostics[0].hint
    casmech.loads(model("lateral", ", driver: {lateral: 20 mm}"))
    with pytest.raises(ModelError) as units:
        casmech.loads(model("lateral", ", driver: {lateral: 20 deg}"))
    assert "joints[0].driver.lateral" in units.value.diagnostics[0].path
    with pytest.raises(ModelError) as motor:
        casmech.loads(model("lateral", ", motor: {torque: 1}"))
    assert "lateral | lateral_speed | lateral_force" in motor.value.diagnostics[0].hint


def test_unregistered_the_format_is_restored(lateral):
    """Registering the kind adds its keys to the JSON Schema; unregistering it (and its joint
    type) restores the format exactly."""
    assert '"lateral_speed"' in export.schema_text()
    joint_types.unregister(SLIDER.name)
    coordinate_kinds.unregister(LATERAL.name)
    try:
        assert export.schema_text() == export.DEFAULT_PATH.read_text(encoding="utf-8")
        assert "lateral" not in JOINT_COORDINATES
    finally:
        coordinate_kinds.register(LATERAL)
        joint_types.register(SLIDER)


def random_pose(rng) -> tuple[np.ndarray, np.ndarray]:
    """A random position and rotation matrix."""
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return rng.normal(size=3), q * np.sign(np.linalg.det(q))


@pytest.mark.parametrize("name", ["angle", "displacement", "lateral"])
def test_each_kinds_driver_row_holds_at_its_measure(lateral, name):
    """A kind's driver row with f = its measure is 0 over any two body frames (the driver and
    the coordinate read the same value), and depends on f there (the driver row's one DOF)."""
    kind = coordinate_kinds.REGISTRY[name]
    primitive, template, _ = kind.driver
    quantity = {"u": U, "v": np.cross(AXIS, U), "w": AXIS, "P": AT}
    rng = np.random.default_rng(7)
    f = ca.SX.sym("f")
    for _ in range(5):  # five random pairs of body poses
        poses = {"i": random_pose(rng), "j": random_pose(rng)}

        def local(where: str, poses=poses):
            """A joint-frame quantity carried by body i or j, in its frame."""
            name_, side = where.split("@")
            r, a = poses[side]
            return ca.DM(a.T @ (quantity[name_] - r) if name_ == "P" else a.T @ quantity[name_])

        frames = [primitives.Frame(ca.DM(r), ca.DM(a)) for r, a in poses.values()]
        value = kind.measure(*frames, *(local(where) for where in kind.vectors.values()))
        vectors = {key: local(where) for key, where in template.items()}
        row = primitives.phi(primitive, frames, vectors, f)
        at = ca.Function("at", [f], [row, ca.jacobian(row, f)])
        phi, slope = (float(v) for v in at(value))
        # one evaluation of the two formulas at a random pose: rounding (1e-12)
        np.testing.assert_allclose(phi, 0.0, rtol=0, atol=1e-12)
        assert abs(slope) > 0.5
