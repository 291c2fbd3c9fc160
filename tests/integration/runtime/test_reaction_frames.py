"""Reactions in body and joint frames (runtime.reaction_frames): the global ones rotated, at
random poses and along a dynamics run of a mechanism with every joint type; in the joint frame a
joint carries no load along the motions it allows; about a `point`, Newton-Euler of the body."""


import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import casmech
from casmech.errors import ModelError, UsageError
from casmech.runtime import reaction_frames
from casmech.runtime.results import Result, table
from tests.conftest import MODELS, ROOT

ZOO = ROOT / "tests" / "helpers" / "joint_zoo.yaml"  # every joint type, oblique axes
VECTORS = ("fx", "fy", "fz", "tx", "ty", "tz")


@pytest.fixture(scope="module")
def zoo():
    return casmech.compile(casmech.load(ZOO), "interpreted")


def random_poses(functions, rows: int, seed: int) -> Result:
    """States at random poses (unit Euler parameters), velocities, accelerations and
    multipliers: the rotation of a vector needs no consistent state."""
    rng = np.random.default_rng(seed)
    nb, n, m = functions.n_bodies, functions.n_coordinates, functions.n_rows
    p = Rotation.random(rows * nb, random_state=seed).as_quat()[:, [3, 0, 1, 2]]  # e0 first
    q = np.hstack([rng.normal(size=(rows, 3 * nb)), p.reshape(rows, 4 * nb)])
    result = Result("dynamics")
    result.extend(np.linspace(0, 1, rows), q, rng.normal(size=(rows, n)),
                  rng.normal(size=(rows, n)), rng.normal(size=(rows, m)))
    return result


def vectors(names, values, joint: str) -> np.ndarray:
    """(rows, 2, 3): a joint's force and torque columns."""
    start = names.index(f"{joint}.fx")
    return values[:, start:start + 6].reshape(-1, 2, 3)


def attitude(names, values, body: str) -> np.ndarray:
    """A of a body at every row from its Euler-parameter columns (scipy; ground: I)."""
    if body == "ground":
        return np.broadcast_to(np.eye(3), (len(values), 3, 3))
    e = np.column_stack([values[:, names.index(f"{body}.e{k}")] for k in (1, 2, 3, 0)])
    return Rotation.from_quat(e).as_matrix()


def frame_of(functions, names, values, joint, frame: str) -> np.ndarray:
    """R (rows, 3, 3): the frame's axes in global components, from scipy's attitudes."""
    meta = next(j for j in functions.joints if j.name == joint)
    if frame == "body_j":
        return attitude(names, values, meta.body_j)
    a_i = attitude(names, values, meta.body_i)
    if frame == "body_i":
        return a_i
    ir_joint = next(j for j in functions.ir.joints if j.name == joint)
    return a_i @ reaction_frames.joint_axes(ir_joint)


def assert_rotated_back(functions, result):
    """Every frame's reactions, rotated back by R, equal the global ones."""
    names, global_values = table(functions, result, "global")
    for frame in ("body_i", "body_j", "joint"):
        _, local_values = table(functions, result, frame)
        for joint in (j.name for j in functions.joints):
            rotation = frame_of(functions, names, global_values, joint, frame)
            back = np.einsum("rab,rkb->rka", rotation, vectors(names, local_values, joint))
            expected = vectors(names, global_values, joint)
            # rotations of O(1..100) vectors in double precision: 1e-12 of the largest
            scale = max(1.0, np.max(np.abs(expected)))
            np.testing.assert_allclose(back / scale, expected / scale, rtol=0, atol=1e-12,
                                       err_msg=f"{joint} in {frame}")
        others = [k for k, name in enumerate(names) if name.split(".")[-1] not in VECTORS]
        np.testing.assert_array_equal(local_values[:, others], global_values[:, others])


def test_body_rotations_equal_scipy_at_random_orientations():
    """A(p) of every body at every row against scipy's quaternion matrix (to 1e-14: a few
    roundings of unit-size products); a non-unit p is normalised first."""
    p = Rotation.random(60, random_state=3).as_quat()[:, [3, 0, 1, 2]].reshape(20, 3, 4)
    a = reaction_frames.body_rotations(1.5 * p)
    expected = Rotation.from_quat(p.reshape(-1, 4)[:, [1, 2, 3, 0]]).as_matrix()
    np.testing.assert_allclose(a[:, :3].reshape(-1, 3, 3), expected, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(a[:, 3], np.broadcast_to(np.eye(3), (20, 3, 3)))  # ground


def test_frames_rotate_back_to_global_at_random_poses(zoo):
    assert_rotated_back(zoo, random_poses(zoo, 40, seed=7))


def test_joint_axes_are_the_joints_own(zoo):
    """U is orthonormal and right-handed, its w the joint's unit `axis` (the zoo's bodies start
    unrotated, so body i's frame is the global one at the file's pose)."""
    model = casmech.load(ZOO)
    for joint in zoo.ir.joints:
        u = reaction_frames.joint_axes(joint)
        np.testing.assert_allclose(u.T @ u, np.eye(3), rtol=0, atol=1e-15)  # roundoff of unit
        assert np.linalg.det(u) == pytest.approx(1.0, abs=1e-15)
        axis = next(j for j in model.joints if j.name == joint.name).vectors.get("axis")
        if axis is not None:
            np.testing.assert_allclose(u[:, 2], axis / np.linalg.norm(axis), rtol=0, atol=1e-15)


# joint -> reaction components that are zero in the joint frame (w = axis): the motions it
# allows, free of drivers and motors (docs/format.md: the torque is about the joint point)
FREE = {
    "r1": ["tz"],  # revolute: rotation about w
    "cy3": ["fz", "tz"],  # cylindrical: sliding along and turning about w (its rsda is a force)
    "pl5": ["fx", "fy", "tz"],  # planar: in-plane sliding, rotation about the normal w
    "s7": ["tx", "ty", "tz"],  # spherical: any rotation about the joint point
}


@pytest.fixture(scope="module")
def zoo_run(zoo):
    return casmech.analyze(zoo, t_end=0.2, output_step=0.02, rtol=1e-8, atol=1e-10)


def test_dynamics_run_rotates_back_and_frees_the_joint_axes(zoo, zoo_run):
    assert_rotated_back(zoo, zoo_run)
    names, global_values = table(zoo, zoo_run, "global")
    _, local = table(zoo, zoo_run, "joint")
    scale = np.max(np.abs(global_values[:, [n.endswith(VECTORS) for n in names]]))
    for joint, free in FREE.items():
        columns = [names.index(f"{joint}.{c}") for c in free]
        # zero up to the roundoff of the multipliers (scale ~10 N): 1e-12 of the largest
        np.testing.assert_allclose(local[:, columns] / scale, 0.0, rtol=0, atol=1e-12,
                                   err_msg=joint)
        if joint != "s7":  # ... while in global axes they are not (the axes are oblique)
            assert np.max(np.abs(global_values[:, columns])) > 1e-3 * scale, joint


def yaml_with_frames(frames: dict[str, str]) -> str:
    text = ZOO.read_text(encoding="utf-8")
    for joint, frame in frames.items():
        written = f"{{name: {joint}, "
        text = text.replace(written, f"{written}reactions: {{frame: {frame}}}, ")
    return text


def test_yaml_key_sets_each_joints_frame(zoo, zoo_run):
    """`reactions: {frame: ...}` per joint gives the table a mapping gives (the others stay
    global), and the DataFrame's metadata says which frame each joint's columns are in."""
    chosen = {"r1": "joint", "p2": "body_i", "u4": "body_j"}
    functions = casmech.compile(casmech.loads(yaml_with_frames(chosen), "zoo.yaml"),
                                "interpreted")
    assert reaction_frames.chosen(functions.ir) == {j.name: chosen.get(j.name, "global")
                                                    for j in functions.joints}
    result = Result("dynamics")
    result.extend(zoo_run.times, zoo_run.q, zoo_run.q_dot, zoo_run.q_ddot, zoo_run.lam)
    result.functions = functions
    np.testing.assert_array_equal(table(functions, result)[1], table(zoo, result, chosen)[1])
    described = result.to_dataframe().attrs["metadata"]["reaction_frames"]
    assert described["r1"] == {"frame": "joint", "body": "ground", "axes": {
        axis: zoo.ir.joints[0].geometry[f"{axis}@i"].tolist() for axis in "uvw"}}
    assert described["p2"] == {"frame": "body_i", "body": "b1"}
    assert described["u4"] == {"frame": "body_j", "body": "b3"}
    assert described["s7"] == {"frame": "global"}


def test_a_run_wide_frame_replaces_the_files(zoo_run):
    functions = casmech.compile(casmech.loads(yaml_with_frames({"r1": "joint"}), "zoo.yaml"),
                                "interpreted")
    assert set(reaction_frames.chosen(functions.ir, "body_j").values()) == {"body_j"}
    assert reaction_frames.chosen(functions.ir, {"s7": "joint"})["r1"] == "joint"


@pytest.mark.parametrize("override, message", [
    ("local", "reaction frame 'local' is not one of global, body_i, body_j, joint"),
    ({"nope": "joint"}, "reaction frames for nope: no such joint"),
])
def test_a_bad_frame_asked_for_is_a_usage_error(zoo, override, message):
    with pytest.raises(UsageError, match=message):
        reaction_frames.chosen(zoo.ir, override)


@pytest.mark.parametrize("frame, hint", [
    ("body-j", "did you mean 'body_j'"),
    ("cm", "the frame of the joint's reaction columns: global (the default)"),
])
def test_a_bad_frame_name_is_a_located_error(frame, hint):
    text = yaml_with_frames({"s7": frame})
    line = next(k for k, row in enumerate(text.splitlines(), 1) if "name: s7" in row)
    with pytest.raises(ModelError) as caught:
        casmech.loads(text, "zoo.yaml")
    message = str(caught.value)
    assert message.startswith(f"zoo.yaml:{line}:"), message
    assert "error[E103]" in message and "joints[6].reactions.frame" in message, message
    assert "global | body_i | body_j | joint" in message and hint in message, message


# A spinning body hung from ground by a ball joint written with the body as body_i: the joint's
# reaction ON ground about the body's CM (`point`, carried by body_i), in the body's frame, is
# minus the body's Newton-Euler equations there: F = m (g - a), T = -(J alpha + w x J w).
TOP = """\
casmech: 1
name: top
bodies:
  - {name: bar, mass: 2.0, inertia: [0.3, 0.25, 0.1, 0.01, 0.0, 0.02], position: [0.3, 0.1, -0.5],
     angular_velocity: [1.0, -2.0, 3.0]}
joints:
  - {name: ball, type: spherical, body_i: bar, body_j: ground, at: [0, 0, 0],
     reactions: {frame: body_i, point: [0.3, 0.1, -0.5]}}
analysis: {type: dynamics, t_end: 0.5, output_step: 0.05, rtol: 1.0e-10, atol: 1.0e-12}
"""


def test_reaction_about_a_point_in_body_frame_is_newton_euler():
    model = casmech.loads(TOP, "top.yaml")
    functions = casmech.compile(model, "interpreted")
    result = casmech.analyze(functions)
    names, values = table(functions, result)
    force, torque = vectors(names, values, "ball").transpose(1, 0, 2)
    a = attitude(names, values, "bar")
    column = {c: values[:, [names.index(f"bar.{c}{k}") for k in "xyz"]]
              for c in ("a", "w", "alpha")}
    to_body = lambda v: np.einsum("rab,ra->rb", a, v)  # noqa: E731  A^T v
    w, alpha = to_body(column["w"]), to_body(column["alpha"])
    inertia = model.bodies[0].inertia
    expected_torque = -(alpha @ inertia.T + np.cross(w, w @ inertia.T))
    expected_force = to_body(2.0 * (np.asarray(model.gravity) - column["a"]))
    # the accelerations and the multipliers solve one linear system at each row: they agree
    # to roundoff of terms of ~20 N and ~1 N m (1e-11 leaves ~1e3 ulps of margin)
    np.testing.assert_allclose(force, expected_force, rtol=0, atol=1e-11)
    np.testing.assert_allclose(torque, expected_torque, rtol=0, atol=1e-11)
    described = result.to_dataframe().attrs["metadata"]["reaction_frames"]["ball"]
    assert described == {"frame": "body_i", "body": "bar",
                         "point": {"body": "bar", "position": [0.0, 0.0, 0.0]}}


def test_reaction_point_at_the_joint_point_changes_nothing(zoo, zoo_run):
    """`point:` at the joint's own point (`at`) gives the default table bit for bit (the arm
    is exactly 0 in body i's frame)."""
    text = ZOO.read_text(encoding="utf-8").replace(
        "{name: r1, ", "{name: r1, reactions: {point: [0, 0, 0]}, ")
    functions = casmech.compile(casmech.loads(text, "zoo.yaml"), "interpreted")
    np.testing.assert_array_equal(table(functions, zoo_run)[1], table(zoo, zoo_run)[1])


def test_a_components_reaction_point_is_placed_like_its_joint_point(tmp_path):
    """In a component instance (placed, the hind legs turned half a turn), a `point` written
    as the joint's `at` stays on the placed `at`."""
    (tmp_path / "components").mkdir()
    leg = (MODELS / "components" / "leg.yaml").read_text(encoding="utf-8")
    (tmp_path / "components" / "leg.yaml").write_text(leg.replace(
        "    at: [0, 0, -L1]\n", "    at: [0, 0, -L1]\n    reactions: {point: [0, 0, -L1]}\n"))
    (tmp_path / "legs.yaml").write_text((MODELS / "quadruped_legs.yaml").read_text())
    knees = [j for j in casmech.load(tmp_path / "legs.yaml").joints if j.name.endswith("knee")]
    assert len(knees) == 4
    for knee in knees:  # the same placement of the same numbers
        np.testing.assert_array_equal(knee.reaction_point, knee.vectors["at"])
