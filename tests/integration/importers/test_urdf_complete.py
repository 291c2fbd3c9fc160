"""URDF import of robots as they are published: example-robot-data's 69 URDFs (read from the
installed package, skipped without it), massless links, fixed-only robots, mirrored meshes,
inertias refused at the URDF's line or repaired on request, and meshes found through
package://, --mesh-dir and the ROS environment."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest

import casmech
from casmech.cli import main
from casmech.errors import ModelError, UsageError
from casmech.importers.emit import to_yaml
from casmech.importers.urdf import import_urdf

DOF = {"revolute": 1, "continuous": 1, "prismatic": 1, "planar": 3, "floating": 6, "fixed": 0}
# the two URDFs whose inertias casmech refuses (a massive link with zero inertia; principal
# moments violating the triangle inequality) import with MuJoCo's repairs, asked for
REPAIRS = {"icub.urdf": ["--bound-inertia", "1e-6"], "icub_reduced.urdf": ["--bound-inertia",
                                                                           "1e-6"],
           "romeo_small.urdf": ["--balance-inertia"],
           "romeo_laas_small.urdf": ["--balance-inertia"]}


def robots_folder() -> Path:
    try:
        distribution = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed (pip install example-robot-data)")
    return Path(distribution.locate_file("cmeel.prefix/share/example-robot-data"))


def expected_dof(path: Path) -> int:
    """Degrees of freedom counted from the URDF by ElementTree alone: each moving joint's,
    less those of joints below which no link has mass (the importer locks them), less one per
    <mimic> joint coupled to another moving joint (the importer's coupler)."""
    root = ET.parse(path).getroot()
    mass = {}
    for link in root.findall("link"):
        element = link.find("inertial/mass")
        mass[link.get("name")] = float(element.get("value")) if element is not None else 0.0
    children: dict[str, list] = {}
    for joint in root.findall("joint"):  # not a <transmission>'s
        children.setdefault(joint.find("parent").get("link"), []).append(joint)

    def below(link: str) -> float:
        return mass[link] + sum(below(j.find("child").get("link"))
                                for j in children.get(link, []))

    moving = {j.get("name"): j for j in root.findall("joint")
              if below(j.find("child").get("link")) > 0 and DOF[j.get("type")]}
    coupled = [j for j in moving.values()
               if j.find("mimic") is not None and j.find("mimic").get("joint") in moving]
    return sum(DOF[j.get("type")] for j in moving.values()) - len(coupled)


def import_and_check(path: Path, folder: Path, out: Path, capsys) -> tuple[int, int]:
    code = main(["import", str(path), "-o", str(out), "--quiet", *REPAIRS.get(path.name, [])])
    if code:
        return code, -1
    capsys.readouterr()
    assert main(["check", str(out), "--allow-dir", str(folder)]) == 0, path.name
    found = re.search(r"degrees of freedom: (\d+)", capsys.readouterr().out)
    return code, int(found.group(1))


@pytest.mark.slow
def test_68_of_the_69_example_robot_data_urdfs_import_and_check(tmp_path, capsys):
    """Every URDF of the package but the empty ur3.urdf imports, `casmech check` accepts it,
    and its degrees of freedom are the URDF's (counted independently); about 30 s."""
    folder = robots_folder()
    paths = sorted(folder.glob("robots/**/*.urdf"))
    assert len(paths) == 69
    checked = 0
    for path in paths:
        code, dof = import_and_check(path, folder, tmp_path / f"{path.stem}.yaml", capsys)
        if path.name == "ur3.urdf":
            assert code == 1 and "error[E100] robot: the robot has no <link>" in \
                capsys.readouterr().err
            continue
        assert (code, dof) == (0, expected_dof(path)), path
        checked += 1
    assert checked == 68


@pytest.mark.parametrize("name", ["human_description/robots/human.urdf",
                                  "romeo_description/urdf/romeo.urdf",
                                  "hector_description/robots/quadrotor_base.urdf",
                                  "tiago_description/robots/tiago_dual.urdf",
                                  "icub_description/robots/icub.urdf"])
def test_the_urdfs_refused_before_import_and_check(tmp_path, capsys, name):
    """The cases issue 33 found refused: massless gimbal links (human), massless fingers
    (romeo), a fixed-only quadrotor, mirrored meshes (tiago_dual), zero inertias (icub, with
    --bound-inertia): each imports, checks, and has the URDF's degrees of freedom."""
    folder = robots_folder()
    path = folder / "robots" / name
    assert import_and_check(path, folder, tmp_path / "robot.yaml", capsys) == \
        (0, expected_dof(path))


def test_mirrored_meshes_keep_their_signs(tmp_path):
    folder = robots_folder()
    path = folder / "robots/tiago_description/robots/tiago_dual.urdf"
    text = to_yaml(import_urdf(path, output=tmp_path / "tiago.yaml"))
    scales = set(re.findall(r"scale: \[([^\]]*)\]", text))
    assert "1.0, -1.0, -1.0" in scales and "1.0, 1.0, -1.0" in scales


ROBOT = """<robot name="r">
  <link name="base"><inertial><mass value="2"/><inertia ixx="0.1" iyy="0.1" izz="0.1"/></inertial>
    <visual><geometry><mesh filename="package://mypkg/meshes/base.stl" scale="1 -1 -1"/></geometry>
    </visual></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
  </joint>
  <link name="arm">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.02" izz="0.025"/></inertial>
    <visual><geometry><mesh filename="package://mypkg/meshes/arm.stl"/></geometry></visual>
  </link>
</robot>
"""


def workspace(tmp_path) -> Path:
    """tmp/ws/src/mypkg/{urdf/r.urdf, meshes/base.stl, meshes/arm.stl}; the URDF's path."""
    package = tmp_path / "ws" / "src" / "mypkg"
    (package / "urdf").mkdir(parents=True)
    (package / "meshes").mkdir()
    triangle = ("solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0.1 0 0\n"
                "vertex 0 0.1 0\nendloop\nendfacet\nendsolid s\n")  # check reads meshes
    for name in ("base.stl", "arm.stl"):
        (package / "meshes" / name).write_text(triangle)
    urdf = package / "urdf" / "r.urdf"
    urdf.write_text(ROBOT)
    return urdf


def test_package_meshes_are_found_where_they_are_installed(tmp_path, monkeypatch):
    """package://mypkg/... is found from the URDF's own folders (one is named mypkg), from
    --mesh-dir, or from $ROS_PACKAGE_PATH; the YAML names it relative to its folder when the
    mesh is below it, else by an absolute path whose folder the import reports."""
    urdf = workspace(tmp_path)
    package = urdf.parents[1]
    beside = import_urdf(urdf, output=package / "r.yaml")
    assert [i.data["geometry"][0]["mesh"] for i in beside.bodies] == ["meshes/arm.stl"]
    assert beside.mesh_folder is None and beside.warnings == []
    elsewhere = import_urdf(urdf, output=tmp_path / "out" / "r.yaml")
    assert elsewhere.bodies[0].data["geometry"][0]["mesh"] == str(package / "meshes/arm.stl")
    assert elsewhere.mesh_folder == package / "meshes"
    alone = tmp_path / "alone.urdf"
    alone.write_text(ROBOT)
    for options, environment in (({"mesh_dirs": [tmp_path / "ws" / "src"]}, None),
                                 ({}, str(tmp_path / "ws" / "src"))):
        if environment:
            monkeypatch.setenv("ROS_PACKAGE_PATH", environment)
        found = import_urdf(alone, **options)  # the YAML beside alone.urdf: below it
        assert found.bodies[0].data["geometry"][0]["mesh"] == "ws/src/mypkg/meshes/arm.stl"
    monkeypatch.delenv("ROS_PACKAGE_PATH")
    missing = import_urdf(alone)
    assert missing.bodies[0].data["geometry"][0]["mesh"] == "meshes/arm.stl"
    assert "mesh 'package://mypkg/meshes/arm.stl' not found" in missing.warnings[0].message


def test_import_command_reports_and_allows_the_mesh_folder(tmp_path, capsys):
    urdf = workspace(tmp_path)
    out = tmp_path / "out" / "r.yaml"
    assert main(["import", str(urdf), "-o", str(out)]) == 0
    folder = urdf.parents[1] / "meshes"
    assert f"meshes are read from {folder}: give --allow-dir {folder}" in \
        capsys.readouterr().out
    assert main(["check", str(out)]) == 1
    assert "error[E305]" in capsys.readouterr().err
    assert main(["check", str(out), "--allow-dir", str(folder)]) == 0


def test_fixed_only_robot_and_floating_base(tmp_path):
    """A robot whose links are all fixed (a quadrotor's base) imports as a model with no
    body, with a warning; --floating-base makes its root link a free body."""
    urdf = workspace(tmp_path)
    fixed = urdf.read_text().replace('type="revolute"', 'type="fixed"')
    urdf.write_text(fixed)
    imported = import_urdf(urdf)
    assert imported.bodies == [] and "bodies: []" in to_yaml(imported)
    assert "--floating-base" in imported.warnings[-1].hint
    model = casmech.loads(to_yaml(import_urdf(urdf, floating_base=True)),
                          file=str(urdf.parents[1] / "r.yaml"))
    (body,) = model.bodies
    assert (body.name, body.mass, model.joints) == ("base", 3.0, ())
    urdf.write_text(fixed.replace('<mass value="2"/>', '<mass value="0"/>').replace(
        '<mass value="1"/>', '<mass value="0"/>'))
    with pytest.raises(ModelError, match=r"r.urdf:2:3: error\[E400\].*root link 'base' has no"):
        import_urdf(urdf, floating_base=True)


@pytest.mark.parametrize("inertia, code, words", [
    ('ixx="0" iyy="0" izz="0"', "E401", "the inertia is not positive definite"),
    ('ixx="0.01" iyy="0.01" izz="0.05"', "E402", "the principal moments violate the triangle"),
])
def test_refused_inertias_are_located_in_the_urdf_and_repaired_on_request(tmp_path, inertia,
                                                                           code, words):
    urdf = workspace(tmp_path)
    urdf.write_text(urdf.read_text().replace('ixx="0.01" iyy="0.02" izz="0.025"', inertia))
    with pytest.raises(ModelError) as caught:
        import_urdf(urdf)
    message = caught.value.diagnostics[0].format()
    assert message.startswith(f"{urdf}:8:32: error[{code}] link[arm].inertial: {words}"), \
        message
    assert "--bound-inertia" in message and "--balance-inertia" in message
    repaired = import_urdf(urdf, bound_inertia=1e-4, balance_inertia=True)
    model = casmech.loads(to_yaml(repaired), file=str(urdf.parents[1] / "r.yaml"))
    moments = np.linalg.eigvalsh(model.bodies[0].inertia)
    assert moments.min() >= 1e-4 * (1 - 1e-12)
    assert moments[0] + moments[1] >= moments[2] * (1 - 1e-12)
    assert any(w.code == "E401" and "inertia repaired" in w.message for w in repaired.warnings)


MASSLESS = """<robot name="m">
  <link name="base"/>
  <joint name="a" type="revolute"><parent link="base"/><child link="v"/><axis xyz="0 0 1"/>
  </joint>
  <link name="v"/>
  <joint name="b" type="revolute"><parent link="v"/><child link="w"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 0 1"/></joint>
  <link name="w"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01"/>
  </inertial></link>
</robot>
"""


def test_massless_links_that_cannot_be_merged_are_one_error(tmp_path):
    """Two parallel hinges through a massless link (a planar 2R with no mass in the middle)
    amount to no casmech joint; a massless link carrying two massive branches cannot be
    merged: both are E400 at the massless link (one code for the condition)."""
    path = tmp_path / "m.urdf"
    path.write_text(MASSLESS)
    with pytest.raises(ModelError, match=r"m.urdf:5:3: error\[E400\] link\[v\]: link 'v' has "
                       r"no mass and the joints through it \(a \(revolute, line 3\), b "):
        import_urdf(path)
    path.write_text(MASSLESS.replace("</robot>", '<joint name="c" type="prismatic"><parent '
                                     'link="v"/><child link="x"/></joint><link name="x">'
                                     '<inertial><mass value="1"/><inertia ixx="1" iyy="1" '
                                     'izz="1"/></inertial></link></robot>'))
    with pytest.raises(ModelError, match=r"m.urdf:5:3: error\[E400\] link\[v\]: link 'v' has "
                       r"no mass and carries 2 moving joints \(b, c\)"):
        import_urdf(path)


def test_a_locked_joint_takes_no_velocity(tmp_path):
    path = tmp_path / "m.urdf"
    path.write_text(MASSLESS.replace('<mass value="1"/>', '<mass value="0"/>'))
    with pytest.raises(UsageError, match="velocity of 'b': the joint is locked"):
        import_urdf(path, velocities={"b": 1.0})


def test_mesh_scale_vector_in_the_format(tmp_path):
    """docs/format.md: a mesh's scale is one factor > 0 or three non-zero factors."""
    def body(scale: str) -> str:
        return ("casmech: 1\nname: s\nbodies:\n  - {name: b, mass: 1, inertia: [1, 1, 1], "
                f"position: [0, 0, 0], geometry: [{{mesh: m.stl, scale: {scale}}}]}}\n")

    (item,) = casmech.loads(body("[1, -1, -1]"), file=str(tmp_path / "s.yaml")).bodies[0].geometry
    np.testing.assert_array_equal(item["scale"], [1, -1, -1])  # as written
    for scale, words in (("[1, 0, 1]", "mesh scale factors must be non-zero"),
                         ("-2", "mesh scale must be positive")):
        with pytest.raises(ModelError, match=r"s.yaml:4:\d+: error\[E410\] bodies\[0\]"
                           rf"\.geometry\[0\]\.scale: {words}"):
            casmech.loads(body(scale), file=str(tmp_path / "s.yaml"))
