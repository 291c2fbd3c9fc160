"""What the HTML player draws besides the bodies (io/overlays.py), checked against the results
columns of real runs and against closed forms computed here: reaction vectors written in another
frame turn back into the global ones, a driven crank's motor torque is the joint-frame tz, a
ball's contact force sits at its contact point along the normal with friction against the slip,
trails follow body points, the ground is the contact plane or the lowest point reached, and each
frame's extent holds every part. Collada meshes are read with their node transforms and units."""

import json
import re

import numpy as np
import pytest

import casmech
from casmech import cli
from casmech.io.animate import build_scene, mesh_file
from casmech.io.csv import read_csv
from casmech.io.overlays import build_overlays
from tests.conftest import MODELS
from tests.unit.io.test_animate import conjugate, quaternion, rotate

FOUR_BAR = MODELS / "four_bar.yaml"
BALL = MODELS / "bouncing_ball.yaml"


def run(model, out, *options):
    assert cli.main(["run", str(model), "--out", str(out), *options]) == 0
    names, values = read_csv(out / "results.csv")
    metadata = json.loads((out / "metadata.json").read_text())
    return names, values, metadata


def overlays_of(model_path, names, values, metadata=None, trails=()):
    model = casmech.load(model_path)
    scene = build_scene(model, names, values)
    return model, scene, build_overlays(model, scene, names, values, scene.rows, metadata,
                                        trails)


def column(names, values, name):
    return values[:, names.index(name)]


def arrow(overlays, kind, name):
    found = [a for a in overlays.arrows if a.kind == kind and a.name == name]
    assert len(found) == 1, (kind, name, [(a.kind, a.name) for a in overlays.arrows])
    return found[0]


@pytest.fixture(scope="module")
def four_bar(tmp_path_factory):
    folder = tmp_path_factory.mktemp("four_bar")
    return (run(FOUR_BAR, folder / "global", "--t-end", "0.5"),
            run(FOUR_BAR, folder / "joint", "--t-end", "0.5", "--reactions-frame", "joint"),
            run(FOUR_BAR, folder / "body_j", "--t-end", "0.5", "--reactions-frame", "body_j"))


def test_reactions_in_any_frame_are_drawn_as_the_global_vectors(four_bar):
    (names, values, meta), *others = four_bar
    _, _, reference = overlays_of(FOUR_BAR, names, values, meta)
    for joint in ("crank_pivot", "coupler_pin", "rocker_pin", "rocker_pivot"):
        force = np.column_stack([column(names, values, f"{joint}.f{c}") for c in "xyz"])
        torque = np.column_stack([column(names, values, f"{joint}.t{c}") for c in "xyz"])
        # the global run's columns are drawn as they are (the table's 17 digits, kept exactly)
        np.testing.assert_allclose(arrow(reference, "force", joint).vector, force,
                                   rtol=0, atol=0)
        np.testing.assert_allclose(arrow(reference, "torque", joint).vector, torque,
                                   rtol=0, atol=0)
        for names_k, values_k, meta_k in others:  # rotated back from the joint and body_j frames
            _, _, turned = overlays_of(FOUR_BAR, names_k, values_k, meta_k)
            # one rotation of O(10 N) vectors by matrices built from 17-digit Euler parameters
            np.testing.assert_allclose(arrow(turned, "force", joint).vector, force,
                                       rtol=0, atol=1e-9)
            np.testing.assert_allclose(arrow(turned, "torque", joint).vector, torque,
                                       rtol=0, atol=1e-9)


def test_motor_torque_is_the_joint_frame_tz_about_the_crank_axis(four_bar):
    (names, values, meta), (names_j, values_j, _), _ = four_bar
    _, scene, overlays = overlays_of(FOUR_BAR, names, values, meta)
    motor = arrow(overlays, "motor_torque", "crank_pivot")
    tz = column(names_j, values_j, "crank_pivot.tz")  # the joint frame's w is the crank axis z
    expected = np.column_stack([np.zeros_like(tz), np.zeros_like(tz), tz])
    # two runs of one analysis: the same numbers to rounding of O(10 N m) torques
    np.testing.assert_allclose(motor.vector, expected, rtol=0, atol=1e-9)
    assert np.abs(tz).max() > 0.1  # the check is not of zeros
    # drawn at the crank's pivot, the global origin
    np.testing.assert_allclose(motor.origin, 0 * motor.origin, rtol=0, atol=1e-12)
    assert not [a for a in overlays.arrows if a.kind.startswith("motor") and
                a.name != "crank_pivot"]  # only the driven joint has one


def test_joint_frames_are_the_axes_of_the_joints(four_bar):
    (names, values, meta), _, _ = four_bar
    _, _, overlays = overlays_of(FOUR_BAR, names, values, meta)
    for triad in overlays.triads:  # every revolute axis of the planar four-bar is global z
        # u, v, w orthonormal and right-handed to rounding
        np.testing.assert_allclose(triad.axes.T @ triad.axes, np.eye(3), rtol=0, atol=1e-12)
        assert np.linalg.det(triad.axes) == pytest.approx(1, abs=1e-12)
    pivot = next(t for t in overlays.triads if t.name == "crank_pivot")
    assert pivot.body == -1  # on ground: global
    np.testing.assert_allclose(pivot.axes[:, 2], [0, 0, 1], rtol=0, atol=1e-12)


@pytest.fixture(scope="module")
def ball(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ball")
    names, values, meta = run(BALL, folder / "run", "--t-end", "0.6", "--output-step", "0.0005")
    return names, values, meta


def test_contact_force_at_the_contact_point_along_the_normal(ball):
    names, values, meta = ball
    _, scene, overlays = overlays_of(BALL, names, values, meta)
    normal = arrow(overlays, "normal", "floor")
    friction = arrow(overlays, "friction", "floor")
    gap = column(names, values, "floor.gap")
    touching = gap < 0
    assert touching.sum() >= 2  # the output step catches the first impact
    centre = np.column_stack([column(names, values, f"ball.{c}") for c in "xyz"])
    # P = centre - (r + gap / 2) n with n = z: the middle of the overlap, closed form
    expected = centre - (0.1 + gap / 2)[:, None] * [0, 0, 1]
    np.testing.assert_allclose(normal.origin, expected, rtol=0, atol=1e-12)
    force = column(names, values, "floor.normal_force")
    np.testing.assert_allclose(normal.vector, force[:, None] * [0, 0, 1], rtol=0, atol=0)
    # friction: the column's magnitude against the slip of the ball's point at P
    v = np.column_stack([column(names, values, f"ball.v{c}") for c in "xyz"])
    w = np.column_stack([column(names, values, f"ball.w{c}") for c in "xyz"])
    slip = v + np.cross(w, expected - centre)
    slip[:, 2] = 0
    size = np.linalg.norm(slip, axis=1)
    magnitude = column(names, values, "floor.friction_force")
    rows = touching & (size > 0)
    np.testing.assert_allclose(friction.vector[rows],  # unit direction to rounding
                               -magnitude[rows, None] * slip[rows] / size[rows, None],
                               rtol=1e-12, atol=1e-12)
    assert magnitude[rows].max() > 1  # backspin: friction acts at the impact


def test_ground_is_the_contact_plane_and_else_the_lowest_point(ball, tmp_path):
    names, values, meta = ball
    _, _, overlays = overlays_of(BALL, names, values, meta)
    point, up = overlays.ground
    np.testing.assert_allclose(up, [0, 0, 1], rtol=0, atol=0)
    assert point[2] == 0  # the floor plane at z = 0
    # without the contact element: the lowest point the ball's sphere reaches
    text = BALL.read_text()
    free = tmp_path / "free_ball.yaml"
    free.write_text(text[:text.index("\nforces:\n")] + text[text.index("\nanalysis:\n"):])
    _, _, overlays = overlays_of(free, names, values)
    lowest = (column(names, values, "ball.z") - 0.1).min()
    # the sphere is a polyhedron of 24 x 12 segments: its lowest vertex is a pole or within
    # 1 - cos(pi/12) of the radius
    assert overlays.ground[0][2] == pytest.approx(lowest, abs=0.1 * (1 - np.cos(np.pi / 12)))


def test_each_frames_extent_holds_every_part(four_bar):
    (names, values, meta), _, _ = four_bar
    _, scene, overlays = overlays_of(FOUR_BAR, names, values, meta)
    rotations = scene.rotations()
    for part in scene.parts:
        points = scene.place(part.body, part.points, rotations)  # (F, n, 3)
        apart = np.linalg.norm(points - overlays.centres[:, None], axis=2)
        assert np.all(apart <= overlays.radii[:, None] * (1 + 1e-12))
    # and is not much larger: the four-bar's links span about 2.3 m
    assert np.all(overlays.radii < 3)


def test_trails_follow_body_points(four_bar):
    (names, values, meta), _, _ = four_bar
    point = np.array([1.2, 0.8, 0.0])  # global at t = 0, carried by the coupler
    _, scene, overlays = overlays_of(FOUR_BAR, names, values, meta,
                                     ["coupler@1.2,0.8,0", "rocker"])
    trail, cm = overlays.trails
    assert (trail.chosen, cm.chosen, cm.name) == (True, True, "rocker")
    model = casmech.load(FOUR_BAR)
    coupler = model.bodies[1]
    q0 = coupler.euler_parameters
    local = rotate(conjugate(q0), point - coupler.position)  # independent quaternion algebra
    r = np.column_stack([column(names, values, f"coupler.{c}") for c in "xyz"])
    q = np.column_stack([column(names, values, f"coupler.e{k}") for k in range(4)])
    expected = np.array([r_k + rotate(q_k / np.linalg.norm(q_k), local)
                         for r_k, q_k in zip(r, q, strict=True)])
    # one rotation of O(1 m) points: rounding
    np.testing.assert_allclose(trail.points, expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(cm.points, np.column_stack(
        [column(names, values, f"rocker.{c}") for c in "xyz"]), rtol=0, atol=0)
    # no trail asked: every body's CM, offered but not chosen
    _, _, overlays = overlays_of(FOUR_BAR, names, values, meta)
    assert [(t.name, t.chosen) for t in overlays.trails] == [
        ("crank", False), ("coupler", False), ("rocker", False)]


@pytest.mark.parametrize("trail, message", [
    ("couplr", "no body 'couplr' in the model (did you mean 'coupler'?)"),
    ("coupler@1,2", "expected BODY or BODY@X,Y,Z with three numbers"),
    ("coupler@1,x,2", "expected BODY or BODY@X,Y,Z with three numbers"),
])
def test_a_bad_trail_is_a_usage_error(four_bar, tmp_path, capsys, trail, message):
    (names, values, meta), _, _ = four_bar
    results = tmp_path / "results.csv"
    with open(results, "w") as handle:
        handle.write(",".join(names) + "\n")
        np.savetxt(handle, values, delimiter=",", fmt="%.17g")
    code = cli.main(["animate", str(FOUR_BAR), str(results), "-o", str(tmp_path / "a"),
                     "--trail", trail])
    assert code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not (tmp_path / "a").exists()  # refused before anything is written


COLLADA = """<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="centimeter" meter="0.01"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="tet"><mesh>
    <source id="pos"><float_array id="pos-array" count="12">0 0 0 1 0 0 0 1 0 0 0 1</float_array>
      <technique_common><accessor source="#pos-array" count="4" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="vtx"><input semantic="POSITION" source="#pos"/></vertices>
    <triangles count="2"><input semantic="VERTEX" source="#vtx" offset="0"/>
      <p>0 2 1 0 1 3</p></triangles>
    <polylist count="1"><input semantic="VERTEX" source="#vtx" offset="0"/><vcount>4</vcount>
      <p>0 3 2 1</p></polylist>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="scene">
    <node id="n"><translate>10 0 0</translate><instance_geometry url="#tet"/></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""


def test_collada_mesh_with_node_transform_and_units(tmp_path):
    path = tmp_path / "tet.dae"
    path.write_text(COLLADA)
    points, triangles = mesh_file(path, 2.0)
    tet = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    # translated by the node (10 cm), in metres (0.01), scaled by 2: exact binary-ish numbers
    moved = (tet + [10, 0, 0]) * 0.01 * 2
    faces = {tuple(sorted(map(tuple, points[t].round(12)))) for t in triangles}
    expected = {tuple(sorted(map(tuple, moved[list(t)].round(12))))
                for t in [(0, 2, 1), (0, 1, 3), (0, 3, 2), (0, 2, 1)]}
    assert faces == expected  # the polygon's quad split into two triangles, one a duplicate
    assert len(triangles) == 4


def test_an_unreadable_collada_mesh_is_located(tmp_path, capsys):
    (tmp_path / "bad.dae").write_text("<COLLADA>not a document")
    model = tmp_path / "m.yaml"
    model.write_text(re.sub(r"\n  - name: ball\n", "\n  - name: ball\n", BALL.read_text())
                     .replace("- {sphere: r}", "- {sphere: r}\n      - {mesh: bad.dae}"))
    results = tmp_path / "results.csv"
    results.write_text("t,ball.x,ball.y,ball.z,ball.e0,ball.e1,ball.e2,ball.e3\n0,0,0,1,1,0,0,0\n")
    assert cli.main(["animate", str(model), str(results), "--no-vtk"]) == 1
    err = capsys.readouterr().err
    assert "error[E410]" in err and "bad.dae" in err and "Traceback" not in err


CAPSULE = """\
casmech: 1
name: rod_on_floor
gravity: [0, 0, -9.81]
bodies:
  - name: rod
    mass: 1
    inertia: [0.001, 0.02, 0.02]
    position: [0, 0, 0.3]
    orientation: {axis_angle: {axis: [0, 0, 1], angle: 0.4}}
    geometry: [{cylinder: {radius: 0.05, length: 0.4, axis: x}}]
forces:
  - {name: floor, type: capsule_plane, body_i: ground, body_j: rod,
     normal: {law: linear, stiffness: 1.0e5}}
"""


def test_contact_shapes_are_what_collides(tmp_path):
    model_path = tmp_path / "rod.yaml"
    model_path.write_text(CAPSULE)
    names = ["t"] + [f"rod.{c}" for c in ("x", "y", "z", "e0", "e1", "e2", "e3")]
    q = quaternion([0, 0, 1], 0.4)
    values = np.array([[0, 0, 0, 0.3, *q]])
    _, _, overlays = overlays_of(model_path, names, values)
    shape, = overlays.shapes
    assert (shape.name, shape.body) == ("contact floor", 0)
    # every point of the capsule is its radius away from the axis segment x in [-0.2, 0.2]
    # (the cylinder's axis in the rod's frame): distance to a segment, closed form
    x = np.clip(shape.points[:, 0], -0.2, 0.2)
    distance = np.linalg.norm(shape.points - np.column_stack([x, 0 * x, 0 * x]), axis=1)
    np.testing.assert_allclose(distance, 0.05, rtol=0, atol=1e-12)  # rounding of O(0.2) numbers
    assert shape.points[:, 0].min() == pytest.approx(-0.25, abs=1e-12)  # the rounded ends
    assert shape.points[:, 0].max() == pytest.approx(0.25, abs=1e-12)
    # the ground is the contact's plane (default: z = 0 on ground)
    assert overlays.ground[0][2] == 0
