"""MJCF import: located errors (file:line:col of the MJCF, included files too), warnings for
what is not translated, the options, and the command line."""

from __future__ import annotations

import pytest

import casmech
from casmech.cli import main
from casmech.errors import ModelError, UsageError
from casmech.importers.emit import to_yaml
from casmech.importers.mjcf import import_mjcf

# a double pendulum with a slider; every error test mutates one line of it
GOOD = """<mujoco model="good">
  <compiler angle="degree"/>
  <default>
    <joint damping="0.1"/>
    <default class="arm"><geom density="500"/></default>
  </default>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" axis="0 1 0"/>
      <geom class="arm" type="capsule" fromto="0 0 0 0.4 0 0" size="0.03"/>
      <body name="lower" pos="0.4 0 0">
        <joint name="elbow" axis="0 1 0" ref="10"/>
        <inertial pos="0.2 0 0" mass="1" diaginertia="0.001 0.01 0.01"/>
        <site name="tip" pos="0.4 0 0"/>
      </body>
    </body>
    <body name="cart" pos="0 1 1">
      <joint name="rail" type="slide" axis="1 0 0"/>
      <geom type="box" size="0.1 0.1 0.1"/>
    </body>
  </worldbody>
  <equality>
    <connect body1="cart" body2="world" anchor="0 0 0"/>
  </equality>
  <actuator>
    <motor name="m" joint="shoulder" gear="2"/>
  </actuator>
  <keyframe><key name="bent" qpos="0.3 0.2 0.1"/></keyframe>
</mujoco>
"""


def write(tmp_path, text: str, name: str = "model.xml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def error_of(tmp_path, text: str, **options) -> str:
    with pytest.raises(ModelError) as caught:
        import_mjcf(write(tmp_path, text), **options)
    assert len(caught.value.diagnostics) == 1
    return caught.value.diagnostics[0].format()


def load(tmp_path, text: str, **options):
    path = write(tmp_path, text)
    imported = import_mjcf(path, **options)
    return casmech.loads(to_yaml(imported), file=f"{path}.yaml"), imported


# ---------------------------------------------------------------------------- errors
@pytest.mark.parametrize("old, new, where, code, words", [
    ('<joint name="shoulder" axis="0 1 0"/>', '<joint name="shoulder" axis="0 1 0">', "16:7",
     "E102", "mismatched tag"),
    ('<geom class="arm"', '<geom class="amr"', "10:7", "E300", "unknown default class 'amr'"),
    ('axis="0 1 0"/>', 'axis="0 0 0"/>', "9:7", "E404", "the joint axis is zero"),
    ('<joint name="rail" type="slide"', '<joint name="rail" type="screw"', "18:7", "E102",
     "must be one of hinge, slide, ball, free"),
    ('mass="1"', 'mass="one"', "13:9", "E102", "got: 'one'"),
    ('mass="1"', 'mass="-1"', "13:9", "E400", "the mass is negative"),
    ('mass="1" diaginertia="0.001 0.01 0.01"', 'mass="1"', "13:9", "E100",
     "needs one of diaginertia and fullinertia"),
    ('diaginertia="0.001 0.01 0.01"', 'diaginertia="0.001 0.001 0.01"', "13:9", "E402",
     "triangle inequality"),
    ('diaginertia="0.001 0.01 0.01"', 'diaginertia="0 0.01 0.01"', "13:9", "E401",
     "not positive definite"),
    ('<body name="cart" pos="0 1 1">', '<body name="cart" pos="0 1 1" quat="1 0 0 0" '
     'euler="0 0 1">', "17:5", "E407", "two orientations (quat, euler)"),
    ('body1="cart"', 'body1="crat"', "23:5", "E300", "did you mean 'cart'"),
    ('<geom type="box" size="0.1 0.1 0.1"/>', '<geom type="box" size="0.1 0.1"/>', "19:7",
     "E410", "a box geom needs 3 positive size numbers"),
    ('<geom type="box" size="0.1 0.1 0.1"/>', '<geom type="box" size="0.1 0.1 0.1" '
     'density="0"/>', "17:5", "E400", "moves (it has joints) but has no mass"),
    ('<joint name="rail" type="slide" axis="1 0 0"/>', '<joint name="rail" type="slide" '
     'axis="1 0 0"/><joint name="twist" axis="0 1 0" pos="0.5 0 0"/>', "18:7", "E103",
     "amount to no casmech joint"),
    ('<joint name="rail" type="slide" axis="1 0 0"/>', '<freejoint/><joint name="rail"/>',
     "18:7", "E103", "a free joint with other joints"),
    ('<worldbody>', '<worldbody><joint name="j"/>', "7:14", "E103", "a joint in <worldbody>"),
    ('<compiler angle="degree"/>', '<compiler angle="degree" coordinate="global"/>', "2:3",
     "E103", "coordinate=\"global\" is not supported"),
    ('<motor name="m" joint="shoulder"', '<motor name="m" joint="shouldr"', "26:5", "E300",
     "unknown joint 'shouldr'"),
    ('<compiler angle="degree"/>', '<compiler angle="grad"/>', "2:3", "E102",
     "'angle' of <compiler> must be one of degree, radian"),
    ('<default class="arm">', '<default>', "5:5", "E100", "a nested <default> has no 'class'"),
    ('<key name="bent" qpos="0.3 0.2 0.1"/>', '<key name="bent" qpos="0.3 0.2"/>', "28:13",
     "E102", "'qpos' of <key> must be 3 finite numbers"),
])
def test_malformed_mjcf_gives_a_located_error(tmp_path, old, new, where, code, words):
    assert old in GOOD
    message = error_of(tmp_path, GOOD.replace(old, new, 1),
                       keyframe="bent" if "qpos" in new else None)
    assert message.startswith(f"{tmp_path / 'model.xml'}:{where}: error[{code}]"), message
    assert words in message


def test_doctype_and_root_are_refused(tmp_path):
    message = error_of(tmp_path, '<?xml version="1.0"?>\n<!DOCTYPE mujoco [<!ENTITY a "b">]>'
                       + GOOD)
    assert ":2:" in message and "error[E102]" in message and "DOCTYPE" in message
    message = error_of(tmp_path, "<robot name='r'/>")
    assert ":1:1: error[E102]" in message and "not <mujoco>" in message


def test_includes_are_expanded_and_their_errors_located(tmp_path):
    """An included file's elements take part in the model; an error in it names its own file
    and line; includes outside the model's folder, missing, or twice are refused."""
    (tmp_path / "parts").mkdir()
    part = tmp_path / "parts" / "cart.xml"
    part.write_text('<mujoco>\n  <worldbody>\n    <body name="extra" pos="2 0 1">\n'
                    '      <joint axis="0 0 0"/>\n    </body>\n  </worldbody>\n</mujoco>\n')
    text = GOOD.replace("</worldbody>", '</worldbody>\n  <include file="parts/cart.xml"/>')
    message = error_of(tmp_path, text)
    assert message.startswith(f"{part}:4:7: error[E404]"), message
    part.write_text(part.read_text().replace('axis="0 0 0"', 'axis="1 0 0"').replace(
        "<joint", '<geom size="0.1"/><joint'))
    model, _ = load(tmp_path, text)
    assert "extra" in [b.name for b in model.bodies]
    for name, code, words in (("../outside.xml", "E305", "leads outside the model's folder"),
                              ("parts/none.xml", "E300", "not found"),
                              ("model.xml", "E103", "included twice")):
        message = error_of(tmp_path, GOOD.replace("<worldbody>",
                                                  f'<include file="{name}"/>\n  <worldbody>'))
        assert f"model.xml:7:3: error[{code}]" in message and words in message, message


def test_inertia_repairs_are_options_with_warnings(tmp_path):
    text = GOOD.replace('diaginertia="0.001 0.01 0.01"', 'diaginertia="0.001 0.001 0.01"')
    model, imported = load(tmp_path, text, balance_inertia=True)
    lower = next(b for b in model.bodies if b.name == "lower")
    assert sorted(lower.inertia.diagonal()) == pytest.approx([0.004] * 3, rel=1e-12)
    (warning,) = [w for w in imported.warnings if w.code == "E401"]
    assert "13:9" in warning.format() and "inertia repaired" in warning.message
    model, _ = load(tmp_path, text.replace('<compiler angle="degree"/>',
                                           '<compiler angle="degree" balanceinertia="true"/>'))
    assert model.bodies[1].inertia.diagonal().min() > 0.0039  # the compiler's own attribute


def test_bounds_on_size_nesting_and_includes(tmp_path, monkeypatch):
    """Hostile files end in a located error in bounded time: too large (E006), bodies nested
    too deep (E105, before any recursion), includes nested too deep (E105)."""
    import casmech.importers

    deep = "<mujoco><worldbody>" + "<body>" * 5000 + "</body>" * 5000 + "</worldbody></mujoco>"
    message = error_of(tmp_path, deep)
    assert ":1:" in message and "error[E105]" in message and "more than 200 levels" in message
    for k in range(10):
        write(tmp_path, f'<mujoco><include file="i{k + 1}.xml"/></mujoco>', f"i{k}.xml")
    message = error_of(tmp_path, '<mujoco><include file="i0.xml"/></mujoco>')
    assert "i7.xml:1:9: error[E105] include: includes nest more than 8 levels" in message
    monkeypatch.setattr(casmech.importers.source, "MAX_SOURCE_BYTES", 1000)
    message = error_of(tmp_path, GOOD + "<!--" + "x" * 2000 + "-->")
    assert f"{tmp_path / 'model.xml'}:1:1: error[E006]" in message


# ---------------------------------------------------------------------------- translation
def test_translation_of_the_good_model(tmp_path):
    model, imported = load(tmp_path, GOOD)
    assert [(j.name, j.type, j.body_i, j.body_j) for j in model.joints] == [
        ("shoulder", "revolute", "ground", "upper"), ("elbow", "revolute", "upper", "lower"),
        ("rail", "translational", "ground", "cart"), ("connect1", "spherical", "ground",
                                                        "cart")]
    assert [f.type for f in model.forces] == ["rsda", "rsda", "tsda"]  # the default damping
    shoulder = next(item for item in imported.joints if item.data["name"] == "shoulder")
    assert shoulder.data["motor"] == {"torque": "2.0*(1.0*ctrl_m)"}
    assert imported.parameters == [("ctrl_m", 0.0, "control of actuator m (line 26): ctrl 0")]
    assert imported.warnings == []


def test_untranslated_elements_are_warnings_with_lines(tmp_path):
    text = GOOD.replace('<joint name="elbow" axis="0 1 0" ref="10"/>',
                        '<joint name="elbow" axis="0 1 0" ref="10" armature="0.1"/>\n'
                        '        <camera name="c"/><replicate count="2"/>').replace(
        "<equality>", '<tendon><fixed name="t"><joint joint="rail" coef="1"/></fixed></tendon>'
        '\n  <sensor><jointpos joint="rail"/></sensor>\n  <equality>\n'
        '    <joint joint1="shoulder" joint2="elbow"/>')
    _, imported = load(tmp_path, text)
    lines = [w.format().split("\n")[0].split(": ", 1)[1] for w in imported.warnings]
    assert lines == [
        "warning[E101] tendon: <tendon><fixed> not translated",
        "warning[E101] sensor: <sensor> with 1 sensors not translated (casmech's results "
        "hold positions, velocities and reactions)",
        "warning[E101] body[lower]: <replicate> not translated",
        "warning[E101] joint[elbow].armature: armature not translated (reflected inertia on "
        "the joint's diagonal of the mass matrix: no casmech element)",
        "warning[E101] equality[joint1]: <joint> equality not translated: a coupling of two "
        "joints' coordinates (rows over two joints' coordinates do not exist in casmech yet)"]
    line = text.split("\n").index("    <joint joint1=\"shoulder\" joint2=\"elbow\"/>") + 1
    assert any(note.startswith(f"equality joint joint1 (line {line} of") for note in
               imported.trailer)


def test_keyframe_and_joint_values(tmp_path):
    """The keyframe's qpos poses the bodies (the elbow's ref of 10 degrees is the file's
    pose); --position overrides one joint; unknown names are usage errors."""
    import numpy as np

    model, _ = load(tmp_path, GOOD, keyframe="bent", positions={"rail": 0.25})
    cart = next(b for b in model.bodies if b.name == "cart")
    np.testing.assert_allclose(cart.position, [0.25, 1, 1], rtol=0, atol=1e-15)  # exact
    lower = next(b for b in model.bodies if b.name == "lower")
    # shoulder 0.3 and elbow 0.2 rad, that is 0.2 - 10 degrees from the file's pose, about y
    angle = 0.3 + 0.2 - np.radians(10)
    np.testing.assert_allclose(lower.position, [0.4 * np.cos(0.3) + 0.2 * np.cos(angle), 0,
                                                1 - 0.4 * np.sin(0.3) - 0.2 * np.sin(angle)],
                               rtol=0, atol=1e-14)  # closed form of the same rotations
    with pytest.raises(UsageError, match="--keyframe bnet: no such <key>; did you mean 'bent'"):
        import_mjcf(write(tmp_path, GOOD), keyframe="bnet")
    with pytest.raises(UsageError, match="'elbo' is not a hinge or slide.*did you mean 'elbow'"):
        import_mjcf(write(tmp_path, GOOD), positions={"elbo": 1.0})


def test_command_line(tmp_path, capsys):
    path = write(tmp_path, GOOD)
    out = tmp_path / "good.yaml"
    assert main(["import", str(path), "-o", str(out), "--keyframe", "bent"]) == 0
    assert f"-> {out}: 3 bodies, 4 joints, 3 forces; 0 warnings" in capsys.readouterr().out
    assert casmech.load(out).name == "good"
    assert main(["import", str(path), "--floating-base"]) == 2
    assert "--floating-base is not an option of a '.xml' import" in capsys.readouterr().err
    with pytest.raises(SystemExit) as done:
        main(["import", "--help"])
    assert done.value.code == 0
    help_text = capsys.readouterr().out
    assert "URDF" in help_text and "MJCF" in help_text and "--keyframe" in help_text


CONTACT = """<mujoco model="contact">
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1" friction="0.3"/>
    <body name="ball" pos="0 0 0.1">
      <freejoint/>
      <geom type="sphere" size="0.1" mass="2" solref="0.01 1"/>
    </body>
    <body name="crate" pos="1 0 0.05">
      <freejoint/>
      <geom type="box" size="0.1 0.1 0.05" mass="1" friction="0.5"/>
    </body>
    <body name="ghost" pos="2 0 1">
      <freejoint/>
      <geom type="sphere" size="0.1" contype="2" conaffinity="2"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_contacts_follow_their_documented_law(tmp_path):
    """A sphere and a box on the floor plane become sphere_plane and points_plane contacts
    (a geom whose bits miss the plane's gets none) with the linear law of docs/import.md:
    the ball settles at the depth m g / k = g (tc zeta)^2 (tc = the mean of its solref and the
    plane's default 0.02), and the crate, pushed at v0, slides v0^2 / (2 mu g) with mu the
    larger friction coefficient (Coulomb)."""
    import numpy as np

    _, imported = load(tmp_path, CONTACT)
    kinds = {item.data["body_j"]: item.data["type"] for item in imported.forces}
    assert kinds == {"ball": "sphere_plane", "crate": "points_plane"}
    tc, g, v0, mu = (0.01 + 0.02) / 2, 9.81, 1.0, 0.5
    next(item for item in imported.bodies if item.data["name"] == "crate").data["velocity"] = \
        [v0, 0.0, 0.0]
    functions = casmech.compile(casmech.loads(to_yaml(imported), file=str(tmp_path / "c.yaml")))
    result = casmech.analyze(functions, "dynamics", t_end=1.0, output_step=0.5, rtol=1e-9,
                             atol=1e-11)
    names, values = casmech.results_table(functions, result)
    column = {name: values[:, k] for k, name in enumerate(names)}
    # settled (critically damped, tc = 15 ms): the static depth g tc^2 = 2.2 mm to 1e-6 m
    np.testing.assert_allclose(column["ball.z"][-1], 0.1 - g * tc ** 2, rtol=0, atol=1e-6)
    # Coulomb sliding; the regularized friction's creep and the contact's compliance are
    # below 1 % of the 0.1 m slide
    np.testing.assert_allclose(column["crate.x"][-1] - 1, v0 ** 2 / (2 * mu * g), rtol=1e-2)
