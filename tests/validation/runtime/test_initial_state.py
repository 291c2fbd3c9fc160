"""Joints' `initial:` values (docs/format.md#initial-state): the bodies posed along the spanning
tree and loops assembled with the values held, checked against the IFToMM A02 exact solution,
against the same mechanisms posed by hand with sin and cos (a second formulation of the pose),
against closed-form velocities, and across the rp, romega and joint formulations; every error
path located at its key."""

import math

import numpy as np
import pytest

import casmech
from casmech.errors import ModelError
from tests.conftest import MODELS, Table
from tests.helpers.reference_data import MOTION, columns, read_analytic, rotation

A02 = (MODELS / "validation" / "iftomm_a02_four_bar_N2.yaml").read_text()


def a02_in_reference_pose(angle: float, rate: float) -> str:
    """The A02 N = 2 model with its bodies in the reference pose (cranks up, as written) and
    no velocities in the file: only the first crank's pivot says where and how fast it starts."""
    text = A02.replace("velocity: [-w * L/2, 0, 0], angular_velocity: [0, 0, w], geometry",
                       "geometry")
    text = text.replace("velocity: [-w * L, 0, 0], geometry", "geometry")
    assert "velocity" not in text[text.index("bodies:"):]
    return text.replace("at: [0, 0, 0], axis: [0, 0, 1]}",
                        f"at: [0, 0, 0], axis: [0, 0, 1],\n     initial: {{angle: {angle!r}, "
                        f"angle_dot: {rate!r}}}}}", 1)


def test_a02_from_the_reference_pose_with_the_cranks_angle_matches_the_exact_solution():
    """Started at t1 = 0.5 s of the exact solution by the crank's angle and rate alone (the
    other cranks and the couplers follow through the loops), the tip B0 of crank0 follows
    the exact solution from t1 on, through the singular flat poses."""
    exact = read_analytic("A02_Nfourbar_N2_0-10s.csv")
    k = int(np.argmin(np.abs(exact["t"] - 0.5)))
    phi = exact["phi"][k]  # the crank's angle from +x; pi/2 in the file's pose
    rate = -exact["vx_B0"][k] * np.sin(phi) + exact["vy_B0"][k] * np.cos(phi)
    text = a02_in_reference_pose(float(phi - np.pi / 2), float(rate)).replace("t_end: 10",
                                                                              "t_end: 4")
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions, "dynamics", formulation="rp")
    table = Table(*casmech.results_table(functions, result))
    tip = columns(table, "crank0", MOTION["Pos"]) + rotation(
        columns(table, "crank0", MOTION["Quat"])) @ np.array([0.0, 0.5, 0.0])
    rows = len(table["t"])
    np.testing.assert_allclose(table["t"] + exact["t"][k], exact["t"][k:k + rows], rtol=0,
                               atol=1e-9)  # the same grid, shifted by t1
    assert np.ptp(exact["phi"][k:k + rows]) > 2 * np.pi  # flat poses passed on the way
    error = np.hypot(tip[:, 0] - exact["x_B0"][k:k + rows], tip[:, 1] - exact["y_B0"][k:k + rows])
    assert error.max() <= 1e-5  # the existing A02 test's requirement (measured 6e-9 m)
    # the crank's angle column starts at the value given, and every crank turns with it
    np.testing.assert_allclose([table["ground0.angle"][0], table["ground2.angle"][0]],
                               phi - np.pi / 2, rtol=0, atol=1e-12)  # assembled to 1e-12
    np.testing.assert_allclose(table["ground1.angle_dot"][0], rate, rtol=1e-12, atol=0)


DOUBLE = """\
casmech: 1
name: double
parameters: {L: 1.0, m: 1.0, w: 0.04, theta1: 1.1, theta2: -0.7, rate1: 0.8, rate2: -1.9}
bodies:
  - {name: rod1, mass: m, inertia: [0.0834, 0.0834, 0.0003], %s}
  - {name: rod2, mass: m, inertia: [0.0834, 0.0834, 0.0003], %s}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: rod1, at: [0, 0, 0], axis: [0, 1, 0]%s}
  - {name: elbow, type: revolute, body_i: rod1, body_j: rod2, at: [%s], axis: [0, 1, 0]%s}
analysis: {type: dynamics, t_end: 1, output_step: 0.05, rtol: 1.0e-10, atol: 1.0e-12}
"""
BY_HAND = DOUBLE % (
    "position: [-L/2*sin(theta1), 0, -L/2*cos(theta1)], orientation: {axis_angle: {axis: "
    "[0, 1, 0], angle: theta1}}, angular_velocity: [0, rate1, 0], velocity: "
    "[-L/2*cos(theta1)*rate1, 0, L/2*sin(theta1)*rate1]",
    "position: [-L*sin(theta1) - L/2*sin(theta1 + theta2), 0, -L*cos(theta1) - "
    "L/2*cos(theta1 + theta2)], orientation: {axis_angle: {axis: [0, 1, 0], angle: theta1 + "
    "theta2}}, angular_velocity: [0, rate1 + rate2, 0], velocity: [-L*cos(theta1)*rate1 - "
    "L/2*cos(theta1 + theta2)*(rate1 + rate2), 0, L*sin(theta1)*rate1 + L/2*sin(theta1 + "
    "theta2)*(rate1 + rate2)]",
    "", "-L*sin(theta1), 0, -L*cos(theta1)", "")
IN_JOINTS = DOUBLE % ("position: [0, 0, -L/2]", "position: [0, 0, -3*L/2]",
                      ", initial: {angle: theta1, angle_dot: rate1}", "0, 0, -L",
                      ", initial: {angle: theta2, angle_dot: rate2}")


@pytest.mark.parametrize("formulation", ["rp", "joint"])
def test_a_tree_posed_by_its_joints_moves_as_the_same_tree_posed_by_hand(formulation):
    """The double pendulum hanging in the file with its joints' angles and rates given moves
    exactly as the one whose bodies the file places with sin and cos at those angles (and
    their velocities by hand): two formulations of the same initial state."""
    runs = []
    for text in (BY_HAND, IN_JOINTS):
        functions = casmech.compile(casmech.loads(text))
        result = casmech.analyze(functions, "dynamics", formulation=formulation)
        runs.append(Table(*casmech.results_table(functions, result)))
    names = [n for n in runs[0].names if n.split(".")[-1] not in ("angle", "angle_dot")]
    moving = [n for n in names if n.split(".")[-1] in ("x", "y", "z", "e0", "e1", "e2", "e3",
                                                      "vx", "vy", "vz", "wx", "wy", "wz")]
    for name in names:  # every column but the joint angles, which count from different poses
        np.testing.assert_allclose(runs[1][name][0], runs[0][name][0], rtol=0,
                                   atol=1e-12)  # the same initial state, to round-off
    for name in moving:
        np.testing.assert_allclose(runs[1][name], runs[0][name], rtol=0,
                                   atol=1e-6)  # both integrated to rtol 1e-10
    np.testing.assert_allclose(runs[1]["pivot.angle"][0], 1.1, rtol=0, atol=1e-14)
    np.testing.assert_allclose(runs[1]["elbow.angle_dot"][0], -1.9, rtol=0,
                               atol=1e-12)  # the given rate, assembled


SPATIAL = """\
casmech: 1
name: spatial
bodies:
  - {name: base, mass: 2, inertia: [0.1, 0.2, 0.3], position: [1, 2, 3],
     velocity: [0.5, -0.2, 0.1], angular_velocity: [0.3, -0.4, 0.7]}
  - {name: cup, mass: 1, inertia: [0.01, 0.02, 0.03], position: [1, 2, 2]}
  - {name: fork, mass: 1, inertia: [0.01, 0.02, 0.03], position: [2, 2, 3]}
  - {name: slider, mass: 1, inertia: [0.01, 0.02, 0.03], position: [1, 3, 3]}
joints:
  - {name: ball, type: spherical, body_i: base, body_j: cup, at: [1, 2, 2.5],
     initial: {orientation: {axis_angle: {axis: [1, 1, 0], angle: 0.9}},
               angular_velocity: [0.2, -1.1, 0.6]}}
  - {name: cross, type: universal, body_i: base, body_j: fork, at: [1.5, 2, 3],
     axis_i: [0, 0, 1], axis_j: [0, 1, 0],
     initial: {angle_i: 0.4, angle_i_dot: 1.3, angle_j: -0.8, angle_j_dot: 0.5}}
  - {name: barrel, type: cylindrical, body_i: base, body_j: slider, at: [1, 2.5, 3],
     axis: [0, 1, 0], initial: {angle: -2.5, angle_dot: 0.9, displacement: 0.2,
                                displacement_dot: -0.3}}
analysis: {type: assembly}
"""


def _axis_rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    skew = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * skew + (1 - np.cos(angle)) * skew @ skew


def test_spherical_universal_and_cylindrical_values_on_a_floating_base():
    """A floating base (its file velocity kept) carries a ball, a universal and a cylindrical
    joint with initial values: each child's pose and velocity by rigid-body kinematics
    (rotation matrices and omega x r, numpy), and the joint-state columns read back what was
    given (their formulas are the results table's, not the posing's)."""
    functions = casmech.compile(casmech.loads(SPATIAL))
    table = Table(*casmech.results_table(functions, casmech.analyze(functions)))
    v0, w0 = np.array([0.5, -0.2, 0.1]), np.array([0.3, -0.4, 0.7])
    base = np.array([1.0, 2, 3])
    for name, point, rotation_, relative_w, slide in (
            ("cup", [1, 2, 2.5], _axis_rotation([1, 1, 0], 0.9), [0.2, -1.1, 0.6], 0.0),
            ("fork", [1.5, 2, 3], _axis_rotation([0, 0, 1], 0.4) @ _axis_rotation(
                [0, 1, 0], -0.8), None, 0.0),
            ("slider", [1, 2.5, 3], _axis_rotation([0, 1, 0], -2.5), [0, 0.9, 0], 0.2)):
        point = np.asarray(point, float)
        file_position = {"cup": [1, 2, 2], "fork": [2, 2, 3], "slider": [1, 3, 3]}[name]
        expected = point + rotation_ @ (np.asarray(file_position, float) - point)
        if name == "slider":
            expected = expected + slide * np.array([0, 1, 0])
        got = np.array([table[f"{name}.{c}"][0] for c in "xyz"])
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)  # exact kinematics
        a = rotation(np.array([[table[f"{name}.e{k}"][0] for k in range(4)]]))[0]
        np.testing.assert_allclose(a, rotation_, rtol=0, atol=1e-12)  # body axes = file's at 0
        if name == "fork":
            w_rel = 1.3 * np.array([0, 0, 1]) + 0.5 * _axis_rotation([0, 0, 1], 0.4) @ [0, 1, 0]
        elif name == "cup":
            w_rel = np.asarray(relative_w, float)
        else:
            w_rel = np.asarray(relative_w, float)
        omega = np.array([table[f"{name}.w{c}"][0] for c in "xyz"])
        np.testing.assert_allclose(omega, w0 + w_rel, rtol=0, atol=1e-12)  # omega adds up
        velocity = np.array([table[f"{name}.v{c}"][0] for c in "xyz"])
        anchor = point + (slide * np.array([0, 1, 0]) if name == "slider" else 0)
        expected_v = v0 + np.cross(w0, anchor - base) + np.cross(omega, got - anchor)
        if name == "slider":
            expected_v = expected_v + (-0.3) * np.array([0, 1, 0])
        np.testing.assert_allclose(velocity, expected_v, rtol=0, atol=1e-12)
    half = np.sin(0.45) / np.sqrt(2)
    np.testing.assert_allclose([table[f"ball.e{k}"][0] for k in range(4)],
                               [np.cos(0.45), half, half, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose([table[f"ball.w{c}"][0] for c in "xyz"], [0.2, -1.1, 0.6],
                               rtol=0, atol=1e-12)  # the relative angular velocity given
    for column, value in {"cross.angle_i": 0.4, "cross.angle_i_dot": 1.3, "cross.angle_j": -0.8,
                          "cross.angle_j_dot": 0.5, "barrel.angle": -2.5,
                          "barrel.angle_dot": 0.9, "barrel.displacement": 0.2,
                          "barrel.displacement_dot": -0.3}.items():
        np.testing.assert_allclose(table[column][0], value, rtol=0, atol=1e-12)
    np.testing.assert_allclose([table[f"base.v{c}"][0] for c in "xyz"], v0, rtol=0,
                               atol=1e-14)  # the root's own velocity, kept


FOUR_BAR = """\
casmech: 1
name: four_bar_initial
parameters: {a: 0.5, c: 1.5, d: 2.0, A: 0.5, W: 2.0}
gravity: [0, -9.81, 0]
bodies:
  - {name: crank, mass: 1, inertia: [0.01, 0.02, 0.02], position: [0, a/2, 0]}
  - {name: coupler, mass: 1, inertia: [0.01, 0.4, 0.4], position: [d/2, (a + c)/2, 0]}
  - {name: rocker, mass: 1, inertia: [0.01, 0.2, 0.2], position: [d, c/2, 0]}
joints:
  - {name: crank_pivot, type: revolute, body_i: ground, body_j: crank, at: [0, 0, 0],
     axis: [0, 0, 1]%s}
  - {name: coupler_pin, type: spherical, body_i: crank, body_j: coupler, at: [0, a, 0]}
  - {name: rocker_pin, type: universal, body_i: coupler, body_j: rocker, at: [d, c, 0],
     axis_i: [-(c - a), d, 0], axis_j: [0, 0, 1]}
  - {name: rocker_pivot, type: revolute, body_i: ground, body_j: rocker, at: [d, 0, 0],
     axis: [0, 0, 1]%s}
analysis: {type: dynamics, t_end: 0.5, rtol: 1.0e-10, atol: 1.0e-12}
"""


def four_bar(crank: str = ", initial: {angle: A, angle_dot: W}", rocker: str = "") -> str:
    return FOUR_BAR % (crank, rocker)


def closed_rocker(angle: float) -> float:
    """The rocker's angle from its upright file pose when the crank is at `angle` from its
    upright pose: the open (non-crossed) closure of the loop, by triangle geometry."""
    a, b, c, d = 0.5, math.hypot(2.0, 1.0), 1.5, 2.0
    bx, by = -a * math.sin(angle), a * math.cos(angle)  # the crank's tip
    dx, dy = d - bx, -by
    distance = math.hypot(dx, dy)
    gamma = math.acos((c**2 + distance**2 - b**2) / (2 * c * distance))
    direction = math.atan2(-dy, -dx) - gamma  # the rocker's tip around O4, open branch
    return math.remainder(direction - math.pi / 2, 2 * math.pi)  # in [-pi, pi]


@pytest.mark.parametrize("formulation", ["rp", "romega", "joint"])
def test_a_loop_closes_with_the_crank_held_at_its_value(formulation):
    """The four-bar with its crank's angle and rate given: the rocker's angle is the loop's
    closure (triangle geometry), and the three formulations start the same."""
    functions = casmech.compile(casmech.loads(four_bar()))
    result = casmech.analyze(functions, "dynamics", formulation=formulation)
    table = Table(*casmech.results_table(functions, result))
    np.testing.assert_allclose(table["crank_pivot.angle"][0], 0.5, rtol=0, atol=1e-12)
    np.testing.assert_allclose(table["crank_pivot.angle_dot"][0], 2.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(table["rocker_pivot.angle"][0], closed_rocker(0.5), rtol=0,
                               atol=1e-12)  # assembled to POSITION_TOLERANCE
    assert table["constraint_violation"].max() <= 1e-9


@pytest.mark.parametrize("analysis", ["assembly", "statics", "modal"])
def test_the_initial_values_hold_in_the_other_analyses(analysis, tmp_path):
    """assembly starts where the values say; statics and modal start their search there
    (the four-bar under gravity has one equilibrium per branch: both find the open one)."""
    functions = casmech.compile(casmech.loads(four_bar()))
    result = casmech.analyze(functions, analysis)
    table = Table(*casmech.results_table(functions, result))
    if analysis == "assembly":
        np.testing.assert_allclose(table["rocker_pivot.angle"][0], closed_rocker(0.5), rtol=0,
                                   atol=1e-12)  # the loop's closure
    else:  # an equilibrium of the open branch: its rocker angle closes the loop
        crank = table["crank_pivot.angle"][0]
        np.testing.assert_allclose(table["rocker_pivot.angle"][0], closed_rocker(crank),
                                   rtol=0, atol=1e-9)  # equilibrium to the statics tolerance


def key_at(text: str, marker: str, key: str) -> tuple[int, int]:
    """(line, column) of `key` on the last line of `text` holding `marker`."""
    lines = text.splitlines()
    line = max(k for k, item in enumerate(lines) if marker in item)
    return line + 1, lines[line].index(key, lines[line].index(marker)) + 1


def findings(text: str) -> list:
    with pytest.raises(ModelError) as caught:
        functions = casmech.compile(casmech.loads(text))
        casmech.analyze(functions, "assembly")
    return caught.value.diagnostics


def test_a_second_value_in_a_loop_is_overdetermined_even_when_consistent():
    text = four_bar(rocker=f", initial: {{angle: {closed_rocker(0.5)!r}}}")
    [found] = findings(text)
    assert (found.code, found.path) == ("E504", "joints[3].initial.angle")
    assert (found.source.line, found.source.col) == key_at(text, "initial", "angle")
    assert "overdetermined" in found.message and "rocker_pivot" in found.message


def test_a_value_outside_the_range_of_motion_cannot_be_met():
    """The rocker of this crank-rocker swings through less than a half turn: 2.5 rad from
    upright is out of its reach."""
    [found] = findings(four_bar(crank="", rocker=", initial: {angle: 2.5}"))
    assert (found.code, found.path) == ("E503", "joints[3].initial.angle")
    assert "cannot be met" in found.message and found.hint


@pytest.mark.parametrize(("joint", "key"), [
    ("driver: {angle: 2*t}, initial: {angle: 0.5}", "angle"),
    ("motor: {speed: 2}, initial: {angle_dot: 1}", "angle_dot"),
])
def test_an_initial_value_of_a_driven_coordinate_is_refused(joint, key):
    text = four_bar(crank=", " + joint)
    with pytest.raises(ModelError) as caught:
        casmech.loads(text)
    [found] = caught.value.diagnostics
    assert (found.code, found.path) == ("E412", f"joints[0].initial.{key}")
    assert (found.source.line, found.source.col) == key_at(text, "initial", key)


def test_a_body_velocity_the_joints_give_is_refused():
    text = four_bar().replace("position: [d/2, (a + c)/2, 0]}",
                              "position: [d/2, (a + c)/2, 0], velocity: [1, 0, 0]}")
    with pytest.raises(ModelError) as caught:
        casmech.loads(text)
    [found] = caught.value.diagnostics
    assert (found.code, found.path) == ("E412", "bodies[1].velocity")
    assert "angle_dot" in found.hint


@pytest.mark.parametrize(("initial", "message"), [
    ("{angel: 1}", "did you mean 'angle'?"),
    ("{displacement: 1}", None),
])
def test_keys_a_joint_type_does_not_have_are_unknown(initial, message):
    with pytest.raises(ModelError) as caught:
        casmech.loads(four_bar(crank=f", initial: {initial}"))
    found = caught.value.diagnostics[0]
    assert found.code == "E101" and found.path.startswith("joints[0].initial.")
    if message:
        assert found.hint == message


def test_a_fixed_joint_has_no_initial_key():
    text = four_bar().replace("type: spherical, body_i: crank, body_j: coupler, at: [0, a, 0]}",
                              "type: spherical, body_i: crank, body_j: coupler, at: [0, a, 0],"
                              " initial: {angle: 1}}")
    with pytest.raises(ModelError) as caught:
        casmech.loads(text)
    assert [(d.code, d.path) for d in caught.value.diagnostics] == [
        ("E101", "joints[1].initial.angle")]


PLACED = """\
casmech: 1
name: placed
gravity: [%s]
components:
  rig:
    bodies:
      - {name: arm, mass: 1.0, inertia: [0.02, 0.03, 0.04], position: [0.5, 0, 0]}
      - {name: rod, mass: 0.5, inertia: [0.01, 0.01, 0.002], position: [1, 0, -0.4]}
      - {name: tip, mass: 0.3, inertia: [0.004, 0.004, 0.001], position: [1, 0, -1.1]}
    joints:
      - {name: hinge, type: revolute, body_i: ground, body_j: arm, at: [0, 0, 0],
         axis: [0, 0, 1], initial: {angle: 0.3, angle_dot: 1.2}}
      - {name: ball, type: spherical, body_i: arm, body_j: rod, at: [1, 0, 0],
         initial: {orientation: {axis_angle: {axis: [1, 2, 0], angle: 0.5}},
                   angular_velocity: [0.4, -0.3, 0.9]}}
      - {name: cross, type: universal, body_i: rod, body_j: tip, at: [1, 0, -0.8],
         axis_i: [1, 0, 0], axis_j: [0, 1, 0], initial: {angle_i: -0.2, angle_j_dot: 0.7}}
instances:
  - {name: r, component: rig, position: %s, orientation: {axis_angle: {axis: %s, angle: %r}}}
"""


def test_a_placed_component_starts_from_its_joint_values_as_placed():
    """A rotated and translated instance of a component whose joints carry `initial:` moves
    as the component does under the rotated gravity (a rigid motion of the same run): the
    spherical joint's relative rotation and angular velocity, written in the component's
    axes, are turned with it."""
    axis = np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
    angle, offset, g = 0.7, np.array([0.3, -1.2, 2.0]), np.array([0.0, 0.0, -9.81])
    p = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])
    turn = rotation(p[None, :])[0]
    tables = []
    for gravity, position, turned in ((g, offset, angle), (turn.T @ g, np.zeros(3), 0.0)):
        text = PLACED % (", ".join(repr(float(x)) for x in gravity),
                         [float(x) for x in position], [float(x) for x in axis], turned)
        functions = casmech.compile(casmech.loads(text))
        result = casmech.analyze(functions, "dynamics", t_end=0.5, output_step=0.05,
                                 rtol=1e-11, atol=1e-12)
        tables.append(Table(*casmech.results_table(functions, result)))
    placed, local = tables
    for body in ("r.arm", "r.rod", "r.tip"):
        for keys, tolerance in ((("x", "y", "z"), 1e-8), (("vx", "vy", "vz"), 1e-7),
                                (("wx", "wy", "wz"), 1e-7)):  # rtol 1e-11 runs, rounded apart
            local_vectors = np.column_stack([local[f"{body}.{k}"] for k in keys])
            expected = local_vectors @ turn.T + (offset if keys[0] == "x" else 0)
            np.testing.assert_allclose(np.column_stack([placed[f"{body}.{k}"] for k in keys]),
                                       expected, rtol=0, atol=tolerance)
    for column in ("r.hinge.angle", "r.ball.e0", "r.cross.angle_i", "r.cross.angle_j_dot"):
        # relative states: the same in both (rounded apart as the bodies)
        np.testing.assert_allclose(placed[column], local[column], rtol=0, atol=1e-7)
    for keys in (("e1", "e2", "e3"), ("wx", "wy", "wz")):  # in the joint frame: the placed
        # model's global axes, turned with the instance
        local_vectors = np.column_stack([local[f"r.ball.{k}"] for k in keys])
        np.testing.assert_allclose(np.column_stack([placed[f"r.ball.{k}"] for k in keys]),
                                   local_vectors @ turn.T, rtol=0, atol=1e-7)
    np.testing.assert_allclose([local[f"r.ball.w{k}"][0] for k in "xyz"], [0.4, -0.3, 0.9],
                               rtol=0, atol=1e-12)  # the values given, in the unturned model
