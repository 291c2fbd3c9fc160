"""URDF import: located errors, warnings, the translation of each element, the command line."""

from __future__ import annotations

import numpy as np
import pytest

import casmech
from casmech.cli import main
from casmech.errors import ModelError, UsageError
from casmech.importers import import_file
from casmech.importers.urdf import import_urdf
from tests.helpers.importers import DATA, DECKS

# a pendulum swinging about y, its rod along -z; every test mutates one line of it
GOOD = """<?xml version="1.0"?>
<robot name="pendulum">
  <link name="base"/>
  <joint name="hinge" type="revolute">
    <parent link="base"/>
    <child link="rod"/>
    <origin xyz="0 0 1" rpy="0 0 0"/>
    <axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="5" velocity="3"/>
  </joint>
  <link name="rod">
    <inertial>
      <origin xyz="0 0 -0.5" rpy="0 0 0"/>
      <mass value="2"/>
      <inertia ixx="0.17" ixy="0" ixz="0" iyy="0.17" iyz="0" izz="0.001"/>
    </inertial>
    <visual>
      <origin xyz="0 0 -0.5"/>
      <geometry><cylinder radius="0.02" length="1"/></geometry>
    </visual>
    <collision>
      <geometry><cylinder radius="0.02" length="1"/></geometry>
    </collision>
  </link>
</robot>
"""


def write(tmp_path, text: str, name: str = "robot.urdf"):
    path = tmp_path / name
    path.write_text(text)
    return path


def error_of(tmp_path, text: str) -> str:
    with pytest.raises(ModelError) as caught:
        import_urdf(write(tmp_path, text))
    assert len(caught.value.diagnostics) == 1
    return caught.value.diagnostics[0].format()


def load(tmp_path, text: str, **initial):
    path = write(tmp_path, text)
    imported = import_urdf(path, **initial)
    from casmech.importers.emit import to_yaml

    return casmech.loads(to_yaml(imported), file=str(path) + ".yaml"), imported


# ---------------------------------------------------------------------------- errors
@pytest.mark.parametrize("old, new, where, code, words", [
    ('<axis xyz="0 1 0"/>', '<axis xyz="0 1 0">', "10:5", "E102", "mismatched tag"),
    ('type="revolute"', 'type="ball"', "4:3", "E103", "unsupported joint type 'ball'"),
    ('<child link="rod"/>', '<child link="rdo"/>', "6:5", "E300", "did you mean 'rod'"),
    ('<mass value="2"/>', '<mass value="two"/>', "14:7", "E102", "got: 'two'"),
    ('<mass value="2"/>', '<mass value="-2"/>', "14:7", "E400", "negative"),
    ('<origin xyz="0 0 1" rpy="0 0 0"/>', '<origin xyz="0 0 1 0"/>', "7:5", "E102",
     "must be 3 finite numbers"),
    ('<origin xyz="0 0 1" rpy="0 0 0"/>', '<origin xyz="0 nan 1"/>', "7:5", "E102",
     "finite"),
    ('<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>', "8:5", "E404", "the joint axis is zero"),
    ('<parent link="base"/>', '', "4:3", "E100", "joint 'hinge' has no <parent>"),
    ('<joint name="hinge"', '<joint nmae="hinge"', "4:3", "E100", "no 'name' attribute"),
    ('<robot name="pendulum">', '<robot name="pendulum"><link name="base"/>', "3:3", "E301",
     "a second link named 'base'"),
    ('<parent link="base"/>', '<parent link="rod"/>', "4:3", "E103",
     "part of a loop not connected to the root link"),
    ('<link name="base"/>', '<link name="base"/><link name="spare"/>', "3:22", "E103",
     "2 links have no parent (base, spare)"),
])
def test_malformed_urdf_gives_a_located_error(tmp_path, old, new, where, code, words):
    assert old in GOOD
    message = error_of(tmp_path, GOOD.replace(old, new, 1))
    assert message.startswith(f"{tmp_path / 'robot.urdf'}:{where}: error[{code}]"), message
    assert words in message


def test_massless_moving_leaf_is_locked_with_a_warning(tmp_path):
    """A moving link with no mass below it (no <inertial>, or mass 0) cannot be moved by the
    dynamics: its joint is locked, the link merged into the ground here, and the model has no
    body (with a warning pointing at the joint and one saying nothing moves)."""
    for text in (GOOD.replace(GOOD[GOOD.index("    <inertial>"):GOOD.index("    <visual>")], ""),
                 GOOD.replace('<mass value="2"/>', '<mass value="0"/>')):
        model, imported = load(tmp_path, text)
        assert model.bodies == () and model.joints == ()
        lines = [w.format().split("\n")[0] for w in imported.warnings]
        assert lines == [
            f"{tmp_path / 'robot.urdf'}:4:3: warning[E400] joint[hinge]: revolute joint 'hinge' "
            "locked at 0: nothing below it has mass, so its links are merged into 'base'",
            f"{tmp_path / 'robot.urdf'}:2:1: warning[E103] robot: no link of the robot moves "
            "(every joint is fixed or locked): the model has no body"]


def test_entities_are_refused_before_expansion(tmp_path):
    """A billion-laughs document is refused at its DOCTYPE, in bounded time and memory."""
    laughs = '<!DOCTYPE robot [<!ENTITY a "ha">' + "".join(
        f'<!ENTITY {chr(98 + k)} "{("&" + chr(97 + k) + ";") * 10}">' for k in range(9)) + "]>"
    message = error_of(tmp_path, GOOD.replace('<?xml version="1.0"?>',
                                              '<?xml version="1.0"?>\n' + laughs))
    assert f"{tmp_path / 'robot.urdf'}:2:" in message and "error[E102]" in message
    assert "DOCTYPE or entity declaration" in message


def test_elements_nested_too_deep_are_refused_before_recursion(tmp_path):
    """A URDF whose elements nest past xml_read.MAX_NESTING is a located E105 (the readers walk
    the tree recursively), as MJCF's is (the shared reader)."""
    deep = "<a>" * 300 + "</a>" * 300
    message = error_of(tmp_path, GOOD.replace("</robot>", deep + "</robot>"))
    assert "error[E105]" in message and "more than 200 levels" in message
    assert "URDF trees" in message


def test_not_a_robot_and_too_large(tmp_path, monkeypatch):
    message = error_of(tmp_path, "<xacro:robot xmlns:xacro='x'/>")
    assert ":1:1: error[E102]" in message and "xacro" in message
    import casmech.importers

    monkeypatch.setattr(casmech.importers.source, "MAX_SOURCE_BYTES", 1000)
    message = error_of(tmp_path, GOOD + "<!--" + "x" * 2000 + "-->")
    assert f"{tmp_path / 'robot.urdf'}:1:1: error[E006]" in message


def test_too_many_links(tmp_path, monkeypatch):
    import casmech.schema.repeat

    monkeypatch.setattr(casmech.schema.repeat, "MAX_ITEMS", 2)
    message = error_of(tmp_path, GOOD)
    assert f"{tmp_path / 'robot.urdf'}:11:3: error[E105] robot: the robot has more than 2" \
        in message


def test_unknown_initial_joint_is_a_usage_error(tmp_path):
    with pytest.raises(UsageError, match="'hinj' is not a revolute.*did you mean 'hinge'"):
        import_urdf(write(tmp_path, GOOD), positions={"hinj": 0.1})
    with pytest.raises(UsageError, match="not a finite number"):
        import_urdf(write(tmp_path, GOOD), velocities={"hinge": float("nan")})


# ---------------------------------------------------------------------------- translation
def test_pendulum_translation(tmp_path):
    model, imported = load(tmp_path, GOOD)
    (rod,), (hinge,) = model.bodies, model.joints
    np.testing.assert_allclose(rod.position, [0, 0, 0.5], rtol=0, atol=1e-15)  # exact input
    np.testing.assert_allclose(rod.inertia, np.diag([0.17, 0.17, 0.001]), rtol=0, atol=0)
    assert (hinge.type, hinge.body_i, hinge.body_j) == ("revolute", "ground", "rod")
    assert imported.warnings == []
    (comments,) = [item.comments for item in imported.joints]
    assert comments[1].startswith("URDF limit (line 9): lower -1 rad, upper 1 rad, effort 5 N m, "
                                  "velocity 3 rad/s; lower and upper as the stop `limit:`")
    assert comments[1].endswith("effort 5 N m, velocity 3 rad/s not enforced")
    # the stop of MuJoCo's default softness (tau 0.02 s, critical damping) for the rod's
    # moment of inertia about the hinge: 0.17 + 2 * 0.5^2 kg m^2
    assert hinge.limit == {"lower": -1.0, "upper": 1.0, "stiffness": 0.67 / 0.02**2,
                           "damping": 2 * 0.67 / 0.02}
    (shape,) = rod.geometry
    assert shape["type"] == "cylinder" and shape["axis"] == "z" and shape["length"] == 1
    np.testing.assert_allclose(shape["offset"], 0, rtol=0, atol=0)  # the visual is at the CM


def test_initial_pose_and_rates_give_the_pendulum_s_state(tmp_path):
    """Posed at angle a with rate w about y: the centre of mass is on the circle of radius 0.5
    about the pivot, with velocity w x r."""
    a, w = 0.4, 1.5
    model, _ = load(tmp_path, GOOD, positions={"hinge": a}, velocities={"hinge": w})
    (rod,) = model.bodies
    r = 0.5 * np.array([-np.sin(a), 0, -np.cos(a)])  # Ry(a) applied to (0, 0, -0.5)
    # closed forms of the same rotation: roundoff only
    np.testing.assert_allclose(rod.position, [0, 0, 1] + r, rtol=0, atol=1e-15)
    np.testing.assert_allclose(rod.velocity, np.cross([0, w, 0], r), rtol=0, atol=1e-15)
    np.testing.assert_allclose(rod.angular_velocity, [0, w, 0], rtol=0, atol=1e-15)


def test_pendulum_period_matches_the_closed_form(tmp_path):
    """Small swings of the imported pendulum: period 2 pi sqrt(I_pivot / (m g d))."""
    model, _ = load(tmp_path, GOOD, positions={"hinge": 1e-3})
    functions = casmech.compile(model)
    period = 2 * np.pi * np.sqrt((0.17 + 2 * 0.25) / (2 * 9.81 * 0.5))
    result = casmech.analyze(functions, "dynamics", t_end=period, output_step=period / 2,
                             rtol=1e-10, atol=1e-12)
    names, values = casmech.results_table(functions, result)
    x = values[:, names.index("rod.x")]
    # amplitude 5e-4 m; the small-angle period is exact to O(angle^2) = 1e-6 relative
    np.testing.assert_allclose(x, [x[0], -x[0], x[0]], rtol=1e-5, atol=1e-12)


def test_fixed_joints_merge_and_damping_becomes_forces():
    """arm6.urdf: the camera is merged into the forearm (masses add), the massless tool0 into
    the hand; the revolute damping is an rsda, the prismatic one a tsda along the axis."""
    model = casmech.loads(import_file(DATA / "arm6.urdf")[0], file="arm6.yaml")
    masses = {b.name: b.mass for b in model.bodies}
    assert masses == {"shoulder": 2.0, "upper_arm": 1.5, "forearm": 1.15, "wrist": 0.4,
                      "slider": 0.3, "hand": 0.2}
    assert [j.type for j in model.joints] == ["revolute"] * 4 + ["translational", "revolute"]
    forces = {f.name: f for f in model.forces}
    assert forces["lift_damping"].type == "rsda" and forces["lift_damping"].damping == 0.8
    damper = forces["extend_damping"]
    extend = next(j for j in model.joints if j.name == "extend")
    # the damper's line is the joint axis: points built from it, roundoff only
    np.testing.assert_allclose(damper.vectors["at_j"] - damper.vectors["at_i"],
                               extend.vectors["axis"], rtol=0, atol=1e-15)
    np.testing.assert_allclose(damper.vectors["at_i"], extend.vectors["at"], rtol=0, atol=0)


def test_untranslated_elements_are_warnings_with_lines(tmp_path):
    text = GOOD.replace('<limit lower="-1"', '<dynamics damping="0"/>\n'
                        '    <mimic joint="other"/>\n    <limit lower="-1"').replace(
        "</robot>", '<transmission name="t"/>\n<gazebo/>\n</robot>')
    _, imported = load(tmp_path, text)
    warnings = [w.format() for w in imported.warnings]
    file = tmp_path / "robot.urdf"
    assert [w.split("\n")[0] for w in warnings] == [
        f"{file}:10:5: warning[E101] joint[hinge].mimic: mimic not translated: the URDF has "
        "no joint 'other'",
        f"{file}:27:1: warning[E101] robot: <transmission> not translated",
        f"{file}:28:1: warning[E101] robot: <gazebo> not translated"]


def test_meshes_names_and_odd_links(tmp_path):
    """package:// mesh names lose their package, scales become one number; names that are not
    identifiers are made so; a floating joint leaves a free body."""
    text = GOOD.replace('<cylinder radius="0.02" length="1"/></geometry>\n    </visual>',
                        '<mesh filename="package://arm/meshes/rod.stl" scale="2 2 2"/>'
                        '</geometry>\n    </visual>').replace('"rod"', '"rod-1"')
    text = text.replace("</robot>", '<joint name="rod-1" type="floating"><parent link="base"/>'
                        '<child link="ball"/></joint><link name="ball"><inertial><mass '
                        'value="1"/><inertia ixx="1" iyy="1" izz="1"/></inertial></link>'
                        '</robot>')
    model, imported = load(tmp_path, text)
    assert [b.name for b in model.bodies] == ["rod_1", "ball"]
    assert [j.name for j in model.joints] == ["hinge"]
    (shape,) = model.bodies[0].geometry
    assert (shape["type"], shape["file"], shape["scale"]) == ("mesh", "meshes/rod.stl", 2.0)
    assert "mesh 'package://arm/meshes/rod.stl' not found; written as 'meshes/rod.stl'" in \
        imported.warnings[0].message
    assert any("floating: ball is a free body" in line for line in imported.trailer)


# ---------------------------------------------------------------------------- command line
def test_command_line(tmp_path, capsys):
    out = tmp_path / "arm6.yaml"
    assert main(["import", str(DATA / "arm6.urdf"), "-o", str(out)]) == 0
    assert f"-> {out}: 6 bodies, 6 joints, 2 forces; 0 warnings" in capsys.readouterr().out
    assert casmech.load(out).name == "arm6"
    posed = tmp_path / "posed.yaml"
    assert main(["import", str(DATA / "arm6.urdf"), "-o", str(posed), "--position",
                 "lift=0.5", "--velocity", "pan=1"]) == 0
    assert "Initial joint values (URDF joint: position, velocity): lift: 0.5, 0, pan: 0, 1." \
        in posed.read_text()
    capsys.readouterr()
    assert main(["import", str(DATA / "arm6.urdf"), "--position", "lift=up"]) == 2
    assert "--position expects JOINT=NUMBER, got 'lift=up'" in capsys.readouterr().err
    assert main(["import", str(DATA / "arm6.urdf"), "--velocity", "lfit=1"]) == 2
    assert "did you mean 'lift'" in capsys.readouterr().err
    deck = DECKS / "test_Revolute_Case01.adm"
    assert main(["import", str(deck), "-o", str(tmp_path / "d.yaml"), "--position", "a=1"]) == 2
    assert "--position is not an option of a '.adm' import" in capsys.readouterr().err
    bad = write(tmp_path, GOOD.replace('type="revolute"', 'type="ball"'))
    assert main(["import", str(bad), "-o", str(tmp_path / "bad.yaml")]) == 1
    assert f"{bad}:4:3: error[E103]" in capsys.readouterr().err


def test_dynamics_friction_is_the_joints_coulomb_friction(tmp_path):
    """URDF's dry joint friction (MuJoCo's URDF import: frictionloss) is the joint's Coulomb
    friction, static limit the same; 0 adds none; a negative one is a located error."""
    text = GOOD.replace('<limit lower="-1"', '<dynamics damping="0.2" friction="0.35"/>\n'
                        '    <limit lower="-1"')
    model, imported = load(tmp_path, text)
    (joint,) = imported.joints
    assert joint.data["friction"] == {"coulomb": 0.35}
    assert not imported.warnings
    assert model.joints[0].friction["coulomb"] == model.joints[0].friction["static"] == 0.35
    _, none = load(tmp_path, text.replace('friction="0.35"', 'friction="0"'))
    assert "friction" not in none.joints[0].data
    message = error_of(tmp_path, text.replace('friction="0.35"', 'friction="-1"'))
    assert ":9:5: error[E103] joint[hinge].dynamics: friction -1 is negative" in message
