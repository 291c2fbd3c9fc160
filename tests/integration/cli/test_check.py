"""casmech check (issue 35 item 9): constraints that cannot be met at t = 0 are located errors
(E502) naming the unmet rows at their joints' lines, and `run` names the same rows; a body's
mesh that is missing or unreadable is a located error (E410), as `casmech animate` words it."""

import re

import pytest

from casmech import cli
from tests.conftest import MODELS
from tests.texts import pendulum

LOCATED = re.compile(r"^(?P<file>[^\s:][^:]*):(?P<line>\d+):(?P<col>\d+): "
                     r"error\[(?P<code>E\d{3})\] (?P<path>\S+):", re.M)
TETHER = """\
  - name: tether
    type: distance
    body_i: ground
    body_j: rod2
    at_i: [0, 0, 0]
    at_j: [-L1 * sin(theta1) - L2 * sin(theta2), 0, -L1 * cos(theta1) - L2 * cos(theta2)]
    length: LENGTH
"""


def tethered(tmp_path, length: str):
    """The gallery's double pendulum (links 1 m) with rod2's tip tied to the pivot at
    `length`: the links span at most 2 m."""
    text = (MODELS / "double_pendulum.yaml").read_text().replace(
        "\nanalysis:", TETHER.replace("LENGTH", length) + "\nanalysis:")
    path = tmp_path / "tethered.yaml"
    path.write_text(text)
    line = 1 + text.splitlines().index("  - name: tether")
    return path, line


def test_check_fails_on_a_length_no_pose_reaches(tmp_path, capsys):
    path, line = tethered(tmp_path, "10")
    assert cli.main(["check", str(path)]) == 1
    out, err = capsys.readouterr()
    assert "assembly failed" in out  # the structure is still reported, at the file's pose
    found = [m.groupdict() for m in LOCATED.finditer(err)]
    assert found == [{"file": str(path), "line": str(line), "col": "5", "code": "E502",
                      "path": "tether"}], err
    assert "joint 'tether': |d_ij|^2 = length^2 cannot be met at t = 0" in err
    assert "Traceback" not in out + err


def test_check_accepts_a_length_the_links_reach(tmp_path, capsys):
    path, _ = tethered(tmp_path, "1.5")  # within the 2 m the two links span
    assert cli.main(["check", str(path)]) == 0
    assert "at the assembled configuration" in capsys.readouterr().out


def test_run_names_the_same_row(tmp_path, capsys):
    path, line = tethered(tmp_path, "10")
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out"), "--t-end", "0.1"]) == 3
    err = capsys.readouterr().err
    assert "the constraints cannot be met" in err
    assert f"{path}:{line}:5: joint 'tether': |d_ij|^2 = length^2 (residual" in err
    assert "elbow" not in err and "pivot" not in err  # the joints that can be met are not named


STL = """\
solid tet
facet normal 0 0 -1
 outer loop
  vertex 0 0 0
  vertex 0 0.1 0
  vertex 0.1 0 0
 endloop
endfacet
facet normal 0 -1 0
 outer loop
  vertex 0 0 0
  vertex 0.1 0 0
  vertex 0 0 0.1
 endloop
endfacet
endsolid tet
"""


@pytest.mark.parametrize("mesh, content, words", [
    ("missing.stl", None, "not found"),
    ("broken.stl", "solid x\nfacet normal 0 0 1\n garbage\n", "cannot read mesh 'broken.stl'"),
    ("notes.txt", "hello", "cannot read mesh 'notes.txt'"),
])
def test_check_fails_on_a_mesh_it_cannot_read(tmp_path, capsys, mesh, content, words):
    text = (MODELS / "double_pendulum.yaml").read_text()
    text = text.replace("    geometry: [{box: [w, w, L2]}]",
                        f"    geometry: [{{box: [w, w, L2]}}, {{mesh: {mesh}}}]")
    (tmp_path / "model.yaml").write_text(text)
    if content is not None:
        (tmp_path / mesh).write_text(content)
    assert cli.main(["check", str(tmp_path / "model.yaml")]) == 1
    err = capsys.readouterr().err
    [found] = [m.groupdict() for m in LOCATED.finditer(err)]
    line = 1 + next(k for k, row in enumerate(text.splitlines()) if mesh in row)
    assert (found["code"], found["line"], found["path"]) == (
        "E410", str(line), "bodies[1].geometry[1].mesh")
    assert words in err
    if mesh.endswith(".stl"):
        (tmp_path / mesh).write_text(STL)  # a mesh it reads: accepted
        assert cli.main(["check", str(tmp_path / "model.yaml")]) == 0


@pytest.mark.parametrize("driver, code, words", [
    ("1e300*t", "E411", "the driver's rate reaches 1e+300 rad/s at t = 0 s"),
    ("'if(t < 0.5, t, 1e20*t)'", "E411", "the driver's value reaches 5e+19 rad at t = 0.5 s"),
    ("'log(0.55 - t)'", "E204", "the driver's value is nan at t = 0.6 s"),
])
def test_check_fails_on_a_driver_beyond_plausible_over_the_run(tmp_path, capsys, driver, code,
                                                               words):
    """Each passes the check of its value at t = 0; over the run's grid it does not."""
    (tmp_path / "m.yaml").write_text(pendulum(driver, "kinematics"))
    assert cli.main(["check", str(tmp_path / "m.yaml")]) == 1
    err = capsys.readouterr().err
    [found] = [m.groupdict() for m in LOCATED.finditer(err)]
    assert (found["code"], found["line"], found["path"]) == (code, "12",
                                                             "joints[0].driver.angle"), err
    assert words in err
    (tmp_path / "m.yaml").write_text(pendulum("2*pi*t", "kinematics"))
    assert cli.main(["check", str(tmp_path / "m.yaml")]) == 0


def test_check_fails_on_a_tsda_whose_points_coincide(tmp_path, capsys):
    text = pendulum(analysis="dynamics") + (
        "forces:\n  - {name: spring, type: tsda, body_i: ground, at_i: [0, 0, -1], "
        "body_j: bar, at_j: [0, 0, -1], stiffness: 10, free_length: 0}\n")
    (tmp_path / "m.yaml").write_text(text)
    assert cli.main(["check", str(tmp_path / "m.yaml")]) == 1
    err = capsys.readouterr().err
    [found] = [m.groupdict() for m in LOCATED.finditer(err)]
    assert (found["code"], found["line"], found["path"]) == ("E404", "14", "forces[0].at_j")
    assert "coincide" in err
