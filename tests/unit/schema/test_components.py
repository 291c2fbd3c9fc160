"""Components and instances (docs/components.md): placement is a rigid motion of everything the
component writes (checked against the closed form: the placed run is the rotated and translated
run of the unplaced component under the rotated gravity), instance parameters reach the run and
its metadata through `--set`, and every mistake is located in the file where it is written,
naming the instance."""

from __future__ import annotations

import json

import numpy as np
import pytest

import casmech
from casmech.cli import main
from casmech.schema.bodies import rotation_matrix
from tests.conftest import MODELS, Table

# ------------------------------------------------------------------------------ placement
RIG = """\
components:
  rig:          # every kind of placed quantity: points, axes, c, ground-side a/s, loads
    bodies:
      - {name: arm, mass: 1.0, inertia: [0.02, 0.03, 0.04], position: [0.5, 0, 0],
         velocity: [0, 1, 0], angular_velocity: [0, 0, 2]}
      - {name: rod, mass: 0.5, inertia: [0.01, 0.01, 0.002], position: [1, 0, -0.4],
         velocity: [0, 2, 0], angular_velocity: [0, 0, 2]}
      - {name: tip, mass: 0.3, inertia: [0.004, 0.004, 0.001], position: [1, 0, -1.1],
         velocity: [0, 2, 0], angular_velocity: [0, 0, 2]}
      - {name: puck, mass: 0.2, inertia: [0.001, 0.001, 0.002], position: [0.5, 0, -1],
         velocity: [0, 0.4, 0]}
    joints:
      - {name: hinge, type: revolute, body_i: ground, body_j: arm, at: [0, 0, 0],
         axis: [0, 0, 1]}
      - {name: ball, type: spherical, body_i: arm, body_j: rod, at: [1, 0, 0]}
      - {name: cross, type: universal, body_i: rod, body_j: tip, at: [1, 0, -0.8],
         axis_i: [1, 0, 0], axis_j: [0, 1, 0]}
      - {name: plane, type: cd, c: [0, 0, 1], body_i: ground, s_i: [0, 0, -1], body_j: puck,
         s_j: [0, 0, 0], f: "0"}
      - {name: circle, type: d, body_i: ground, s_i: [0, 0, -1], body_j: puck,
         s_j: [0, 0, 0], f: "0.25"}
      - {name: level, type: dp1, body_i: ground, a_i: [0, 0, 1], body_j: puck,
         a_j: [1, 0, 0], f: "0"}
    forces:
      - {name: spring, type: tsda, body_i: ground, at_i: [0, 1, 0.5], body_j: rod,
         at_j: [1, 0, -0.8], stiffness: 20, damping: 0.5}
      - {name: twist, type: rsda, joint: hinge, stiffness: 1, damping: 0.1}
      - {name: push, type: force, body: tip, at: [1, 0, -1.4], value: ["0.5*sin(3*t)", 0, 1]}
      - {name: turn, type: torque, body: arm, value: [0, 0, "0.2*cos(t)"]}
      - {name: spin, type: torque, body: rod, value: [0.1, 0, 0], frame: body}
"""


def rig(gravity, position=(0, 0, 0), axis=(1, 0, 0), angle=0.0) -> str:
    vector = ", ".join(repr(float(x)) for x in gravity)
    return (f"casmech: 1\nname: rig\ngravity: [{vector}]\n" + RIG + "instances:\n"
            f"  - {{name: r, component: rig, position: {list(position)},\n"
            f"     orientation: {{axis_angle: {{axis: {list(axis)}, angle: {angle!r}}}}}}}\n")


def run(text: str, t_end: float = 0.5):
    model = casmech.loads(text)
    functions = casmech.compile(model)
    result = casmech.analyze(functions, "dynamics", t_end=t_end, output_step=0.05,
                             rtol=1e-11, atol=1e-12)
    return model, Table(*casmech.results_table(functions, result))


def triples(table: Table, prefix: str, keys: tuple[str, str, str]) -> np.ndarray:
    return np.column_stack([table[f"{prefix}.{k}"] for k in keys])


def rotations(table: Table, body: str) -> np.ndarray:
    e = np.column_stack([table[f"{body}.e{k}"] for k in range(4)])
    return np.array([rotation_matrix(p) for p in e])


VECTORS = [("x", "y", "z"), ("vx", "vy", "vz"), ("wx", "wy", "wz"), ("ax", "ay", "az"),
           ("alphax", "alphay", "alphaz")]
REACTIONS = [("fx", "fy", "fz"), ("tx", "ty", "tz")]
# the two runs (rtol 1e-11) round differently; measured largest differences over 0.5 s:
# positions 3.3e-10 m, velocities 1.6e-9 m/s, angular velocities 8.3e-9 rad/s, accelerations
# 1.5e-7 m/s^2 and angular accelerations 1.2e-6 rad/s^2 (on 43 rad/s^2); a misplaced item
# would differ by O(1)
TOLERANCES = [3e-9, 2e-8, 1e-7, 2e-6, 1e-5]


def test_placed_component_moves_as_the_rotated_and_translated_component():
    axis = np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
    angle, offset, g = 0.7, np.array([0.3, -1.2, 2.0]), np.array([0.0, 0.0, -9.81])
    _, placed = run(rig(g, offset.tolist(), axis.tolist(), angle))
    p = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])
    rotation = rotation_matrix(p)
    model, local = run(rig(rotation.T @ g))  # the same motion seen in the component frame
    assert placed.names == local.names
    for body in ("r.arm", "r.rod", "r.tip", "r.puck"):
        for keys, tolerance in zip(VECTORS, TOLERANCES, strict=True):
            expected = triples(local, body, keys) @ rotation.T + (offset if keys[0] == "x" else 0)
            np.testing.assert_allclose(triples(placed, body, keys), expected, rtol=0,
                                       atol=tolerance)
        # as the positions: measured 8e-10
        np.testing.assert_allclose(rotations(placed, body), rotation @ rotations(local, body),
                                   rtol=0, atol=1e-8)
    for joint in ("r.hinge", "r.ball", "r.cross", "r.plane", "r.circle", "r.level"):
        for keys in REACTIONS:
            expected = triples(local, joint, keys) @ rotation.T
            # reactions up to 20 N: measured 7e-8 at most
            np.testing.assert_allclose(triples(placed, joint, keys), expected, rtol=0,
                                       atol=1e-6)
    mass = sum(b.mass for b in model.bodies)
    # potential -sum m g.r: placing by `offset` shifts it by -M g.offset; the rest is invariant
    # (measured 2.6e-9 J on ~30 J)
    np.testing.assert_allclose(placed["energy"], local["energy"] - mass * g @ offset, rtol=0,
                               atol=3e-8)
    assert np.ptp(placed["r.puck.x"]) > 0.05 and np.ptp(placed["r.tip.z"]) > 0.01  # it moves


def test_placement_of_the_resolved_numbers():
    """The placed model holds the numbers a user would write in global coordinates."""
    axis, angle, offset = np.array([0.0, 0.0, 1.0]), np.pi / 2, np.array([1.0, 2.0, 3.0])
    model = casmech.loads(rig((0, 0, -9.81), offset.tolist(), axis.tolist(), angle))
    rotation = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90 deg about z
    bodies = {b.name: b for b in model.bodies}
    joints = {j.name: j for j in model.joints}
    forces = {f.name: f for f in model.forces}
    exact = [  # (value, expected): rotation by hand of the numbers in RIG
        (bodies["r.arm"].position, [1.0, 2.5, 3.0]),
        (bodies["r.arm"].velocity, [-1.0, 0.0, 0.0]),
        (bodies["r.arm"].angular_velocity, [0.0, 0.0, 2.0]),
        (rotation_matrix(bodies["r.puck"].euler_parameters), rotation),
        (joints["r.ball"].vectors["at"], [1.0, 3.0, 3.0]),
        (joints["r.cross"].vectors["axis_i"], [0.0, 1.0, 0.0]),
        (joints["r.cross"].vectors["axis_j"], [-1.0, 0.0, 0.0]),
        (joints["r.plane"].vectors["c"], [0.0, 0.0, 1.0]),
        (joints["r.plane"].vectors["s_i"], [1.0, 2.0, 2.0]),  # ground side: a global point
        (joints["r.plane"].vectors["s_j"], [0.0, 0.0, 0.0]),  # body side: body frame
        (joints["r.level"].vectors["a_i"], [0.0, 0.0, 1.0]),
        (joints["r.level"].vectors["a_j"], [1.0, 0.0, 0.0]),
        (forces["r.spring"].vectors["at_i"], [0.0, 2.0, 3.5]),
        (forces["r.push"].vectors["at"], [1.0, 3.0, 1.6]),
        ([f.value(t=0.5) for f in forces["r.push"].value], [0.0, 0.5 * np.sin(1.5), 1.0]),
        ([f.value(t=0.0) for f in forces["r.turn"].value], [0.0, 0.0, 0.2]),
        ([f.value(t=0.0) for f in forces["r.spin"].value], [0.1, 0.0, 0.0]),  # body frame
    ]
    for value, expected in exact:
        # one rotation by a matrix of 0, +-1 and 6e-17 (cos pi/2) entries: roundoff only
        np.testing.assert_allclose(value, expected, rtol=0, atol=1e-15)
    assert forces["r.twist"].joint == "r.hinge" and joints["r.hinge"].body_i == "ground"


# -------------------------------------------------------------------------------- --set
def test_set_of_an_instance_parameter_changes_the_run_and_is_recorded(tmp_path):
    out = tmp_path / "out"
    argv = ["run", str(MODELS / "chain_repeat.yaml"), "--out", str(out), "--t-end", "0.02",
            "--output-step", "0.01", "--mode", "interpreted", "--set", "link2.m=3"]
    assert main(argv) == 0
    metadata = json.loads((out / "metadata.json").read_text())
    assert metadata["overrides"] == {"link2.m": "3"}
    assert metadata["parameters"]["link2.m"] == 3.0 and metadata["parameters"]["link1.m"] == 1.0
    names = (out / "results.csv").read_text().splitlines()[0].split(",")
    energy = np.loadtxt(out / "results.csv", delimiter=",", skiprows=1)[0, names.index("energy")]
    # t = 0: the straight chain (z = 0: no potential) spins rigidly at w0 about z; each rod has
    # v = w0 x_c and I_zz = m (L^2 + w^2) / 12
    length, width, w0 = 0.5, 0.04, 1.0
    masses = np.array([1.0, 3.0, 1.0, 1.0])
    centres = (np.arange(4) + 0.5) * length
    kinetic = 0.5 * w0**2 * np.sum(masses * (centres**2 + (length**2 + width**2) / 12))
    # the file's velocities satisfy the joints: assembly leaves them, roundoff only
    np.testing.assert_allclose(energy, kinetic, rtol=1e-12, atol=1e-12)
    assert abs(kinetic - 0.5 * w0**2 * np.sum(centres**2 + (length**2 + width**2) / 12)) > 0.1


def test_set_of_an_unknown_instance_names_the_instances(capsys):
    assert main(["check", str(MODELS / "quadruped_legs.yaml"), "--set", "front_lef.m1=2"]) == 1
    err = capsys.readouterr().err
    assert "error[E300] --set front_lef.m1: unknown instance 'front_lef'" in err
    assert "did you mean 'front_left'?" in err


def test_quadruped_centre_of_mass_obeys_newton():
    """Newton for the whole walker: sum m a_z = spring + damper - M g (the guide and the
    driven joints are internal or act across z)."""
    model = casmech.load(MODELS / "quadruped_legs.yaml")
    functions = casmech.compile(model)
    table = Table(*casmech.results_table(functions, casmech.analyze(
        functions, t_end=0.2, output_step=0.01)))
    p = model.parameters
    assert len(model.bodies) == 9 and "hind_left.phase" in p
    force = (p["k"] * (p["top"] - table["trunk.z"] - model.forces[0].free_length)
             - p["c"] * table["trunk.vz"])
    total = sum(b.mass for b in model.bodies)
    inertial = sum(b.mass * table[f"{b.name}.az"] for b in model.bodies)
    # the accelerations solve the equations of motion at each output: measured residual
    # 2e-12 N on forces of ~150 N (1e-9: margin for the solve's conditioning)
    np.testing.assert_allclose(inertial, force - total * 9.81, rtol=0, atol=1e-9)
    assert np.ptp(inertial) > 1.0  # the legs' swing really shakes the trunk


# -------------------------------------------------------------------------------- errors
def write(tmp_path, files: dict[str, str]):
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    return tmp_path


def findings(capsys, path) -> list[str]:
    assert main(["check", str(path)]) == 1
    found = []
    for line in capsys.readouterr().err.splitlines():
        if line.startswith("  ") and found:
            found[-1] += "\n" + line
        else:
            found.append(line)
    return found


def at(path, text: str, needle: str, skip: int = 0) -> str:
    """'path:line:col' of the first character after `needle`'s key (or of `needle`)."""
    lines = text.splitlines()
    for number, line in enumerate(lines, 1):
        if needle in line:
            column = line.index(needle) + 1 + skip
            return f"{path}:{number}:{column}"
    raise AssertionError(f"{needle!r} not in the text")


LEG = """\
casmech: 1
name: leg
parameters: {L: 0.3, m: 1.0}
bodies:
  - {name: thigh, mass: m, inertia: [0.1, 0.1, 0.01], position: [0, 0, -L/2]}
  - {name: shank, mass: m, inertia: [0.1, 0.1, 0.01], position: [0, 0, -1.5*L]}
joints:
  - {name: knee, type: revolute, body_i: thigh, body_j: shank, at: [0, 0, -L], axis: [0, 1, 0]}
"""

PARENT = """\
casmech: 1
name: robot
parameters: {L0: 0.3}
components:
  leg: {file: leg.yaml}
bodies:
  - {name: trunk, mass: 5, inertia: [1, 1, 1], position: [0, 0, 0]}
instances:
  - {name: leg1, component: leg, parameters: {L: 2*L0}, position: [0.2, 0, 0]}
  - {name: leg2, component: leg, position: [-0.2, 0, 0]}
joints:
  - {name: hip1, type: revolute, body_i: trunk, body_j: leg1.thigh, at: [0.2, 0, 0],
     axis: [0, 1, 0]}
"""


def edit(text: str, old: str, new: str) -> str:
    assert old in text
    return text.replace(old, new)


def test_composed_model_without_mistakes_loads(tmp_path):
    path = write(tmp_path, {"leg.yaml": LEG, "robot.yaml": PARENT}) / "robot.yaml"
    model = casmech.load(path)
    assert [b.name for b in model.bodies] == ["trunk", "leg1.thigh", "leg1.shank", "leg2.thigh",
                                              "leg2.shank"]
    assert [j.name for j in model.joints] == ["hip1", "leg1.knee", "leg2.knee"]
    # leg1 gets L = 2 L0 = 0.6: its shank's centre 1.5 L below the hip at x = 0.2
    np.testing.assert_allclose(model.bodies[2].position, [0.2, 0, -0.9], rtol=0, atol=1e-15)
    assert model.parameters["leg1.L"] == pytest.approx(0.6, abs=1e-15)
    assert model.files[str(tmp_path / "leg.yaml")] == LEG
    assert model.joints[1].source.file == str(tmp_path / "leg.yaml")  # inspect shows the leg


ERRORS = {  # name: (files, (file, needle, skip), code, words)
    "unknown_component": (
        {"robot.yaml": edit(PARENT, "leg2, component: leg,", "leg2, component: lge,")},
        ("robot.yaml", "component: lge", 11), "E300",
        ["in instance leg2: unknown component 'lge'", "did you mean 'leg'?"]),
    "unknown_instance": (
        {"robot.yaml": edit(PARENT, "body_j: leg1.thigh", "body_j: leg3.thigh")},
        ("robot.yaml", "body_j: leg3", 8), "E300",
        ["unknown body 'leg3.thigh': there is no instance 'leg3'", "did you mean 'leg"]),
    "unknown_member": (
        {"robot.yaml": edit(PARENT, "body_j: leg1.thigh", "body_j: leg1.thig")},
        ("robot.yaml", "body_j: leg1", 8), "E300",
        ["instance leg1 (component leg) has no body 'thig'", "did you mean 'leg1.thigh'?"]),
    "undeclared_parameter": (
        {"robot.yaml": edit(PARENT, "parameters: {L: 2*L0}", "parameters: {Lx: 2*L0}")},
        ("robot.yaml", "Lx: 2", 0), "E300",
        ["in instance leg1: component leg has no parameter 'Lx'", "did you mean 'L'?"]),
    "parameter_without_value": (
        {"leg.yaml": edit(LEG, "m: 1.0}", "m: ~}"),
         "robot.yaml": edit(PARENT, "leg2, component: leg,", "leg2, component: leg, "
                                                              "parameters: {m: 1},")},
        ("robot.yaml", "{name: leg1", 0), "E100",
        ["in instance leg1: component leg needs a value for its parameter 'm'"]),
    "negative_mass_in_the_component_file": (
        {"leg.yaml": edit(LEG, "mass: m, inertia: [0.1, 0.1, 0.01], position: [0, 0, -1.5",
                          "mass: -m, inertia: [0.1, 0.1, 0.01], position: [0, 0, -1.5")},
        ("leg.yaml", "mass: -m", 6), "E400",
        ["in instances leg1, leg2 (component leg): mass must be positive"]),
    "missing_component_file": (
        {"robot.yaml": edit(PARENT, "file: leg.yaml", "file: legs.yaml")},
        ("robot.yaml", "legs.yaml", 0), "E300", ["cannot read component file 'legs.yaml'"]),
    "duplicate_instance": (
        {"robot.yaml": edit(PARENT, "name: leg2", "name: leg1")},
        ("robot.yaml", "{name: leg1, component: leg, position", 7), "E301",
        ["duplicate instance name 'leg1'"]),
    "cycle_across_files": (
        {"leg.yaml": LEG + "components: {foot: {file: foot.yaml}}\ninstances:\n"
                           "  - {name: f, component: foot}\n",
         "foot.yaml": "casmech: 1\nname: foot\ncomponents: {leg: {file: leg.yaml}}\n"
                      "instances:\n  - {name: back, component: leg}\n"},
        ("foot.yaml", "component: leg", 11), "E103",
        ["in instances leg1.f, leg2.f (component foot): in instance back: component cycle "
         "leg -> foot -> leg"]),
}


@pytest.mark.parametrize("case", sorted(ERRORS))
def test_mistakes_are_located_in_their_file_and_name_the_instance(case, tmp_path, capsys):
    files, (where, needle, skip), code, words = ERRORS[case]
    root = write(tmp_path, {"leg.yaml": LEG, "robot.yaml": PARENT, **files})
    all_files = {"leg.yaml": LEG, "robot.yaml": PARENT, **files}
    found = findings(capsys, root / "robot.yaml")
    assert len(found) == 1, found
    location = at(root / where, all_files[where], needle, skip)
    assert found[0].startswith(f"{location}: error[{code}]"), (found[0], location)
    for word in words:
        assert word in found[0], found[0]


INLINE = """\
casmech: 1
name: loops
components:
  a:
    parameters: {m: 1}
    bodies:
      - {name: bar, mass: m, inertia: [1, 1, 1], position: [0, 0, 0]}
    instances:
      - {name: inner, component: b}
  b:
    bodies:
      - {name: bob, mass: 1, inertia: [1, 1, 1], position: [0, 0, 0]}
    instances:
      - {name: back, component: a}
instances:
  - {name: top, component: a}
"""


def test_cycle_of_inline_components_is_named(tmp_path, capsys):
    path = write(tmp_path, {"loops.yaml": INLINE}) / "loops.yaml"
    found = findings(capsys, path)
    assert len(found) == 1, found
    assert found[0].startswith(f"{at(path, INLINE, 'component: a}', 11)}: error[E103]")
    assert "in instance top.inner (component b): in instance back: component cycle a -> b -> a" \
        in found[0]


def test_mistake_inside_an_inline_component_is_located_in_the_block(tmp_path, capsys):
    text = edit(INLINE, "      - {name: back, component: a}\n", "").replace(
        "mass: 1, inertia: [1, 1, 1]", "mass: 1, inertia: [1, 1, 5]")
    path = write(tmp_path, {"loops.yaml": text}) / "loops.yaml"
    found = findings(capsys, path)
    assert len(found) == 1, found
    assert found[0].startswith(f"{at(path, text, '[1, 1, 5]')}: error[E402]")
    assert "in instance top.inner (component b): principal moments violate" in found[0]


# --------------------------------------------------------------------- laws reading the state
PENDULUM = """\
parameters: {m: 1.0, L: 0.8, k: 2.0, c: 0.05, cd: 0.4, omega0: 4.0}
bodies:
  - {name: rod, mass: m, inertia: [m*L**2/12, m*L**2/12, m*1.0e-4], position: [0, 0, -L/2],
     velocity: [-omega0*L/2, 0, 0], angular_velocity: [0, omega0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: rod, at: [0, 0, 0], axis: [0, 1, 0]}
forces:
  - {name: spring, type: torque, body: rod, value: [0, "-k*pivot.angle - c*pivot.angle_dot", 0]}
  - {name: drag, type: force, body: rod, value: ["-cd*rod.vx*abs(rod.vx)", 0, 0]}
"""


def test_instances_read_their_own_state_in_force_laws():
    """Two instances of a pendulum whose laws read `pivot.angle` and `rod.vx`: each moves as
    the pendulum alone (translated), so each law reads its own instance's state."""
    indented = "".join(f"    {line}\n" for line in PENDULUM.splitlines())
    composed = ("casmech: 1\nname: two\ncomponents:\n  pend:\n" + indented + "instances:\n"
                "  - {name: a, component: pend}\n"
                "  - {name: b, component: pend, position: [2, 0, 0], parameters: {omega0: 2}}\n")
    _, both = run(composed, t_end=1.0)
    for name, omega0, shift in (("a", 4.0, 0.0), ("b", 2.0, 2.0)):
        alone = "casmech: 1\nname: one\n" + PENDULUM.replace("omega0: 4.0", f"omega0: {omega0}")
        _, single = run(alone, t_end=1.0)
        for keys in VECTORS[:3]:
            offset = np.array([shift if keys[0] == "x" else 0.0, 0.0, 0.0])
            expected = triples(single, "rod", keys) + offset
            # two integrations of the same motion (rtol 1e-11): measured 3.5e-9 at most; the
            # other instance's state (another omega0) would be off by O(0.1)
            np.testing.assert_allclose(triples(both, f"{name}.rod", keys), expected, rtol=0,
                                       atol=3e-8)


# ---------------------------------------------------------------------------------- nesting
PAIR = """\
casmech: 1
name: pair
parameters: {m: 1.0}
components:
  leg: {file: leg.yaml}
instances:
  - {name: left, component: leg, position: [0, 0.1, 0], parameters: {m: m}}
  - {name: right, component: leg, position: [0, -0.1, 0],
     orientation: {axis_angle: {axis: [0, 0, 1], angle: pi/2}}}
"""

HERD = """\
casmech: 1
name: herd
components:
  pair: {file: parts/pair.yaml}
instances:
  - {name: p, component: pair, position: [1, 2, 3], parameters: {m: 0.5},
     orientation: {axis_angle: {axis: [1, 0, 0], angle: pi/2}}}
"""


def test_nested_instances_compose_their_frames_and_names(tmp_path):
    root = write(tmp_path, {"parts/leg.yaml": LEG, "parts/pair.yaml": PAIR, "herd.yaml": HERD})
    model = casmech.load(root / "herd.yaml", {"p.right.L": "0.5"})
    bodies = {b.name: b for b in model.bodies}
    assert list(bodies) == ["p.left.thigh", "p.left.shank", "p.right.thigh", "p.right.shank"]
    outer = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # pi/2 about x
    inner = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])  # pi/2 about z
    d_outer = np.array([1.0, 2, 3])
    # left: m from the herd (0.5) through the pair; its shank 1.5 L = 0.45 below its hip
    left = outer @ (np.array([0, 0.1, 0]) + [0, 0, -0.45]) + d_outer
    # right: L = 0.5 by --set p.right.L, turned by both frames
    right = outer @ (inner @ [0, 0, -0.75] + [0, -0.1, 0]) + d_outer
    # two or three rotations by matrices of 0, +-1 and 6e-17: roundoff only
    np.testing.assert_allclose(bodies["p.left.shank"].position, left, rtol=0, atol=1e-15)
    np.testing.assert_allclose(bodies["p.right.shank"].position, right, rtol=0, atol=1e-15)
    np.testing.assert_allclose(rotation_matrix(bodies["p.right.thigh"].euler_parameters),
                               outer @ inner, rtol=0, atol=1e-15)
    assert bodies["p.left.thigh"].mass == 0.5 and bodies["p.right.thigh"].mass == 1.0
    assert model.parameters["p.m"] == 0.5 and model.parameters["p.right.L"] == 0.5
    assert [j.name for j in model.joints] == ["p.left.knee", "p.right.knee"]
    assert set(model.files) == {str(root / "parts/pair.yaml"), str(root / "parts/leg.yaml")}


def test_required_parameter_from_set_and_components_without_bodies():
    text = """\
casmech: 1
name: x
components:
  c:
    parameters: {m: ~, h: 2*m}
    bodies: [{name: b, mass: m, inertia: [1, 1, 1], position: [0, 0, h]}]
  empty:
    bodies:
instances:
  - {name: i1, component: c}
  - {name: nothing, component: empty}
bodies:
"""
    model = casmech.loads(text, overrides={"i1.m": "2.5"})
    assert [(b.name, b.mass) for b in model.bodies] == [("i1.b", 2.5)]
    # h = 2 m follows the value given by --set
    np.testing.assert_allclose(model.bodies[0].position, [0, 0, 5.0], rtol=0, atol=0)
    assert model.parameters["i1.h"] == 5.0
