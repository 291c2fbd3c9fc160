"""casmech animate, VTK side: the .pvd/.vtu series read back with meshio and an XML parser.

The results table is made up here (random unit Euler parameters per row), so every expected point
is computed by this file alone: body-frame shapes from the YAML numbers and closed forms, moved by
r + q x_bar q* with a quaternion product written below (not casmech's A(p)).
"""

import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

from casmech import cli
from casmech.io.animate import RINGS, SEGMENTS
from tests.conftest import MODELS

MODEL = """\
casmech: 1
name: shapes
bodies:
  - name: brick
    mass: 2
    inertia: [1, 1, 1]
    position: [0, 0, 0]
    geometry:
      - box: [0.4, 0.2, 0.1]
        offset: [0.1, -0.05, 0.02]
        orientation: {axis_angle: {axis: [0, 0, 1], angle: 0.7}}
  - name: roller
    mass: 1
    inertia: [1, 1, 1]
    position: [0.5, 0, 0]
    orientation: {axis_angle: {axis: [1, 0, 0], angle: 0.3}}
    geometry:
      - cylinder: {radius: 0.05, length: 0.3, axis: x}
        offset: [0, 0.1, 0]
  - name: ball
    mass: 1
    inertia: [1, 1, 1]
    position: [1, 0, 0.5]
    geometry:
      - {sphere: 0.08, offset: [0, 0, 0.2]}
  - name: blob
    mass: 3
    inertia: [0.3, 0.4, 0.5, 0.02, -0.01, 0.03]
    position: [0, 1, 0]
    orientation: {axis_angle: {axis: [0, 1, 1], angle: 1.1}}
  - name: tet
    mass: 1
    inertia: [1, 1, 1]
    position: [1, 1, 0]
    geometry:
      - mesh: tet.stl
        scale: 2
        offset: [0.1, 0, 0]
        orientation: {axis_angle: {axis: [0, 1, 0], angle: 0.5}}
joints:
  - {name: hinge, type: revolute, body_i: ground, body_j: brick, at: [0, 0, 0], axis: [0, 0, 1]}
  - {name: knuckle, type: spherical, body_i: brick, body_j: roller, at: [0.3, 0.1, 0]}
  - {name: rope, type: distance, body_i: ball, body_j: blob, at_i: [1, 0, 0.6], at_j: [0, 1, 0.2]}
  - {name: c1, type: cd, c: [1, 0, 0], body_i: tet, s_i: [0.1, 0.2, 0.3], body_j: blob,
     s_j: [0, 0, 0.1]}
"""
TET = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
TET_FACES = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
BODIES = ["brick", "roller", "ball", "blob", "tet"]
INITIAL = {  # r0, q0 of each body as the YAML writes them
    "brick": ([0, 0, 0], ([0, 0, 1], 0.0)), "roller": ([0.5, 0, 0], ([1, 0, 0], 0.3)),
    "ball": ([1, 0, 0.5], ([0, 0, 1], 0.0)), "blob": ([0, 1, 0], ([0, 1, 1], 1.1)),
    "tet": ([1, 1, 0], ([0, 0, 1], 0.0)),
}
TIMES = np.linspace(0, 0.5, 6)
SPHERE_POINTS = (RINGS - 1) * SEGMENTS + 2  # UV sphere: rings of SEGMENTS points plus 2 poles
# Points are written as float64 and moved by one rotation: agreement to rounding of O(1) numbers.
RTOL, ATOL = 0, 1e-12


# ------------------------------------------------------------------ independent quaternions
def quaternion(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])


def rotate(q, v):
    """q v q* for a unit quaternion q = [w, x, y, z] and points v (..., 3)."""
    w, e = q[0], np.asarray(q[1:])
    v = np.asarray(v, float)
    t = 2 * np.cross(e, v)
    return v + w * t + np.cross(e, t)


def conjugate(q):
    return np.concatenate([[q[0]], -np.asarray(q[1:])])


def stl_text(points, faces):
    facets = "".join("facet normal 0 0 0\n outer loop\n" + "".join(
        f"  vertex {x} {y} {z}\n" for x, y, z in points[list(face)]) + " endloop\nendfacet\n"
        for face in faces)
    return f"solid tet\n{facets}endsolid tet\n"


def make_case(folder, rows=TIMES, seed=1):
    """The model, tet.stl and a results table of random poses; returns paths and the poses."""
    (folder / "tet.stl").write_text(stl_text(TET, TET_FACES))
    (folder / "shapes.yaml").write_text(MODEL)
    rng = np.random.default_rng(seed)
    r = rng.normal(size=(len(rows), len(BODIES), 3))
    q = rng.normal(size=(len(rows), len(BODIES), 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    names = ["t"] + [f"{b}.{c}" for b in BODIES for c in ("x", "y", "z", "e0", "e1", "e2", "e3")]
    values = np.column_stack([rows, np.concatenate([r, q], axis=-1).reshape(len(rows), -1)])
    names.append("energy")  # columns animate does not use are ignored
    values = np.column_stack([values, np.zeros(len(rows))])
    with open(folder / "results.csv", "w") as handle:
        handle.write(",".join(names) + "\n")
        np.savetxt(handle, values, delimiter=",", fmt="%.17g")
    return folder / "shapes.yaml", folder / "results.csv", r, q


def read_series(out):
    """(timesteps, [meshio.Mesh per frame]) through the .pvd, parsed as XML."""
    root = ET.parse(out / "animation.pvd").getroot()
    assert root.get("type") == "Collection"
    sets = root.find("Collection").findall("DataSet")
    times = np.array([float(s.get("timestep")) for s in sets])
    return times, [meshio.read(out / s.get("file")) for s in sets]


def cell_points(mesh, kind, body, joint):
    """Points used by the cells of one type that carry the given body and joint indices."""
    block = next(k for k, cells in enumerate(mesh.cells) if cells.type == kind)
    pick = ((mesh.cell_data["body"][block] == body)
            & (mesh.cell_data["joint"][block] == joint))
    return mesh.points[np.unique(mesh.cells[block].data[pick])]


def body_frame(points, r, q):
    return rotate(conjugate(q), points - r)


@pytest.fixture(scope="module")
def series(tmp_path_factory):
    folder = tmp_path_factory.mktemp("shapes")
    model, results, r, q = make_case(folder)
    assert cli.main(["animate", str(model), str(results), "-o", str(folder / "out")]) == 0
    return (*read_series(folder / "out"), r, q)


# ---------------------------------------------------------------------------------- tests
def test_one_frame_per_row_with_the_rows_times(series):
    times, meshes, _, _ = series
    np.testing.assert_allclose(times, TIMES, rtol=0, atol=0)  # repr() round-trips exactly
    assert len(meshes) == len(TIMES)


def test_point_counts_per_body(series):
    mesh = series[1][0]
    counts = {b: len(cell_points(mesh, "triangle", k, -1)) for k, b in enumerate(BODIES)}
    assert counts == {"brick": 8, "roller": 2 * SEGMENTS + 2, "ball": SPHERE_POINTS,
                      "blob": SPHERE_POINTS, "tet": 4}


def test_box_corners_follow_the_body(series):
    _, meshes, r, q = series
    turn = quaternion([0, 0, 1], 0.7)
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    corners = [0.1, -0.05, 0.02] + rotate(turn, signs * [0.2, 0.1, 0.05])
    for k, mesh in enumerate(meshes):
        expected = r[k, 0] + rotate(q[k, 0], corners)
        got = cell_points(mesh, "triangle", 0, -1)
        order = np.lexsort(expected.T), np.lexsort(got.T)
        np.testing.assert_allclose(got[order[1]], expected[order[0]], rtol=RTOL, atol=ATOL)


def test_cylinder_and_sphere_surfaces(series):
    _, meshes, r, q = series
    for k, mesh in enumerate(meshes):
        local = body_frame(cell_points(mesh, "triangle", 1, -1), r[k, 1], q[k, 1]) - [0, 0.1, 0]
        radial = np.hypot(local[:, 1], local[:, 2])
        on_rim = radial > 0.025
        np.testing.assert_allclose(radial[on_rim], 0.05, rtol=RTOL, atol=ATOL)
        np.testing.assert_allclose(radial[~on_rim], 0, rtol=RTOL, atol=ATOL)  # cap centres
        np.testing.assert_allclose(np.abs(local[:, 0]), 0.15, rtol=RTOL, atol=ATOL)  # axis x
        ball = body_frame(cell_points(mesh, "triangle", 2, -1), r[k, 2], q[k, 2])
        np.testing.assert_allclose(np.linalg.norm(ball - [0, 0, 0.2], axis=1), 0.08,
                                   rtol=RTOL, atol=ATOL)


def test_default_shape_is_the_inertia_ellipsoid(series):
    """A uniform solid ellipsoid x^T C^-1 x <= 1 has I = m/5 (tr(C) 1 - C), so
    C = 5/m (tr(I)/2 1 - I): every point drawn for 'blob' must satisfy x^T C^-1 x = 1."""
    _, meshes, r, q = series
    inertia = np.array([[0.3, 0.02, -0.01], [0.02, 0.4, 0.03], [-0.01, 0.03, 0.5]])
    c = 5 / 3 * (np.trace(inertia) / 2 * np.eye(3) - inertia)
    for k, mesh in enumerate(meshes):
        local = body_frame(cell_points(mesh, "triangle", 3, -1), r[k, 3], q[k, 3])
        level = np.einsum("ni,ij,nj->n", local, np.linalg.inv(c), local)
        # sphere points are cos/sin of float64 angles scaled: 1e-12 covers their rounding
        np.testing.assert_allclose(level, 1.0, rtol=0, atol=1e-12)


def test_stl_mesh_scaled_offset_and_turned(series):
    _, meshes, r, q = series
    local = [0.1, 0, 0] + rotate(quaternion([0, 1, 0], 0.5), 2 * TET)
    for k, mesh in enumerate(meshes):
        expected = r[k, 4] + rotate(q[k, 4], local)
        got = cell_points(mesh, "triangle", 4, -1)
        order = np.lexsort(expected.T), np.lexsort(got.T)
        np.testing.assert_allclose(got[order[1]], expected[order[0]], rtol=RTOL, atol=ATOL)


def _carried(point, body, r, q, k):
    """Where a point of body (given GLOBAL at t = 0, in the file's pose) is at frame k."""
    r0, (axis, angle) = INITIAL[body]
    local = rotate(conjugate(quaternion(axis, angle)), np.asarray(point, float) - r0)
    index = BODIES.index(body)
    return r[k, index] + rotate(q[k, index], local)


def test_joint_markers_ride_on_their_bodies(series):
    """A marker is a sphere about the joint point: the mean of its UV-sphere points (symmetric
    rings and poles) is that point on each body."""
    _, meshes, r, q = series
    for k, mesh in enumerate(meshes):
        centre = {(j, b): cell_points(mesh, "triangle", b, j).mean(axis=0)
                  for j, b in [(0, -1), (0, 0), (1, 0), (1, 1), (2, 2), (2, 3), (3, 4), (3, 3)]}
        expected = {
            (0, -1): np.zeros(3),  # on ground: stays put
            (0, 0): _carried([0, 0, 0], "brick", r, q, k),
            (1, 0): _carried([0.3, 0.1, 0], "brick", r, q, k),
            (1, 1): _carried([0.3, 0.1, 0], "roller", r, q, k),
            (2, 2): _carried([1, 0, 0.6], "ball", r, q, k),
            (2, 3): _carried([0, 1, 0.2], "blob", r, q, k),
            (3, 4): r[k, 4] + rotate(q[k, 4], [0.1, 0.2, 0.3]),  # cd: body-frame points
            (3, 3): r[k, 3] + rotate(q[k, 3], [0, 0, 0.1]),
        }
        for key, point in expected.items():
            # mean of ~130 points of size ~1: summation rounding stays below 1e-12
            np.testing.assert_allclose(centre[key], point, rtol=0, atol=1e-12, err_msg=str(key))


def test_joints_with_two_points_apart_draw_a_line(series):
    """The distance joint and the cd constraint join two different points; the others do not."""
    _, meshes, r, q = series
    for k, mesh in enumerate(meshes):
        block = next(b for b in range(len(mesh.cells)) if mesh.cells[b].type == "line")
        joints = mesh.cell_data["joint"][block]
        assert sorted(joints) == [2, 3]
        rope, c1 = (mesh.points[mesh.cells[block].data[list(joints).index(j)]] for j in (2, 3))
        np.testing.assert_allclose(rope, [_carried([1, 0, 0.6], "ball", r, q, k),
                                          _carried([0, 1, 0.2], "blob", r, q, k)],
                                   rtol=RTOL, atol=ATOL)
        np.testing.assert_allclose(c1, [r[k, 4] + rotate(q[k, 4], [0.1, 0.2, 0.3]),
                                        r[k, 3] + rotate(q[k, 3], [0, 0, 0.1])],
                                   rtol=RTOL, atol=ATOL)


@pytest.mark.parametrize("option, times", [(["--every", "2"], [0, 0.2, 0.4, 0.5]),
                                           (["--fps", "2.5"], [0, 0.4])])
def test_frame_selection(tmp_path, option, times):
    model, results, _, _ = make_case(tmp_path)
    out = tmp_path / "out"
    assert cli.main(["animate", str(model), str(results), "-o", str(out), "--no-html",
                     *option]) == 0
    got, _ = read_series(out)
    np.testing.assert_allclose(got, times, rtol=0, atol=1e-15)  # rows of the table, not new times
    assert not (out / "animation.html").exists()


def test_results_without_a_body_is_a_usage_error(tmp_path, capsys):
    model, results, _, _ = make_case(tmp_path)
    lines = results.read_text().splitlines()
    keep = [k for k, name in enumerate(lines[0].split(",")) if not name.startswith("tet.")]
    results.write_text("\n".join(",".join(np.array(line.split(","))[keep]) for line in lines))
    assert cli.main(["animate", str(model), str(results), "-o", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert "tet.x" in error and "Traceback" not in error


def test_missing_mesh_file_points_at_its_line(tmp_path, capsys):
    model, results, _, _ = make_case(tmp_path)
    model.write_text(MODEL.replace("mesh: tet.stl", "mesh: gone.stl"))
    line = MODEL.splitlines().index("      - mesh: tet.stl") + 1
    assert cli.main(["animate", str(model), str(results), "-o", str(tmp_path / "out")]) == 1
    error = capsys.readouterr().err
    assert f"{model}:{line}:" in error and "E410" in error and "gone.stl" in error


@pytest.mark.parametrize("option", [["--every", "0"], ["--fps", "-1"]])
def test_bad_frame_options_are_usage_errors(tmp_path, option, capsys):
    model, results, _, _ = make_case(tmp_path)
    assert cli.main(["animate", str(model), str(results), "-o", str(tmp_path / "o"), *option]) == 2
    assert "must be" in capsys.readouterr().err


def test_real_run_keeps_the_pendulum_pivot_at_the_origin(tmp_path):
    """End to end on the ME751 pendulum: the bar's copy of the pivot is fixed by the revolute
    joint, so its marker stays at the origin in every frame."""
    model = MODELS / "me751_pendulum.yaml"
    assert cli.main(["run", str(model), "--out", str(tmp_path), "--t-end", "0.3",
                     "--output-step", "0.05"]) == 0
    assert cli.main(["animate", str(model), str(tmp_path / "results.csv"),
                     "-o", str(tmp_path / "anim")]) == 0
    times, meshes = read_series(tmp_path / "anim")
    np.testing.assert_allclose(times, np.linspace(0, 0.3, 7), rtol=0, atol=1e-12)  # CSV t
    for mesh in meshes:
        pivot = cell_points(mesh, "triangle", 0, 0).mean(axis=0)
        # assembly/kinematics hold constraints to ~1e-10 (results' constraint_violation)
        np.testing.assert_allclose(pivot, 0, rtol=0, atol=1e-8)


def test_quad_mesh_is_split_into_two_triangles_per_quad(tmp_path):
    (tmp_path / "square.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    (tmp_path / "m.yaml").write_text(
        "casmech: 1\nname: tile\nbodies:\n  - name: tile\n    mass: 1\n    inertia: [1, 1, 1]\n"
        "    position: [0, 0, 0]\n    geometry: [{mesh: square.obj, scale: 3}]\n")
    (tmp_path / "r.csv").write_text("t,tile.x,tile.y,tile.z,tile.e0,tile.e1,tile.e2,tile.e3\n"
                                    "0,1,2,3,1,0,0,0\n")
    assert cli.main(["animate", str(tmp_path / "m.yaml"), str(tmp_path / "r.csv"),
                     "-o", str(tmp_path / "out"), "--no-html"]) == 0
    mesh = read_series(tmp_path / "out")[1][0]
    assert len(mesh.cells[0].data) == 2  # one quad, two triangles, no joints
    expected = [1, 2, 3] + 3 * np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    got = mesh.points[np.unique(mesh.cells[0].data)]
    np.testing.assert_allclose(got[np.lexsort(got.T)], expected[np.lexsort(expected.T)],
                               rtol=RTOL, atol=ATOL)
    # the two triangles tile the square: a point inside it near each edge lies in exactly one
    corners = (mesh.points[mesh.cells[0].data] - [1, 2, 3])[:, :, :2] / 3
    for point in [(0.5, 0.2), (0.8, 0.5), (0.5, 0.8), (0.2, 0.5)]:
        inside = 0
        for a, b, c in corners:
            weights = np.linalg.solve(np.column_stack([b - a, c - a]), np.subtract(point, a))
            inside += bool(weights.min() > 0 and weights.sum() < 1)
        assert inside == 1, point


def test_rows_out_of_time_order_are_a_usage_error(tmp_path, capsys):
    model, results, _, _ = make_case(tmp_path, rows=TIMES[::-1])
    assert cli.main(["animate", str(model), str(results), "-o", str(tmp_path / "out")]) == 2
    assert "time order" in capsys.readouterr().err
