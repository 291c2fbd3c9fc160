"""Resolution of good models: numbers, orientations, defaults, functions of time, overrides."""

import math

import casadi
import numpy as np
import pytest

from casmech.core.quaternions import from_matrix
from casmech.errors import ModelError
from casmech.schema import load_model_text
from casmech.schema.bodies import rotation_matrix

# Rotations are computed with a handful of flops from 17-digit inputs: 1e-12 leaves ~1000 ulps
# of room for the trigonometry and Shepperd's square root, and is far below any modelling error.
ROT = {"rtol": 0, "atol": 1e-12}


def rodrigues(axis, angle):
    """Rotation about `axis` by `angle` (Rodrigues' formula, independent of Euler parameters)."""
    u = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def a_of_p(p):
    """A(p) = 2[(e0^2 - 1/2) I + e e^T + e0 e~], written out entry by entry (Haug 6.2.25)."""
    e0, e1, e2, e3 = p
    return 2 * np.array(
        [
            [e0**2 + e1**2 - 0.5, e1 * e2 - e0 * e3, e1 * e3 + e0 * e2],
            [e1 * e2 + e0 * e3, e0**2 + e2**2 - 0.5, e2 * e3 - e0 * e1],
            [e1 * e3 - e0 * e2, e2 * e3 + e0 * e1, e0**2 + e3**2 - 0.5],
        ]
    )


def vec(values):
    return "[" + ", ".join(repr(float(v)) for v in values) + "]"


def body(name, extra, inertia="[1, 1, 1]"):
    return f"  - {{name: {name}, mass: 1, inertia: {inertia}, position: [0, 0, 0], {extra}}}\n"


def model(bodies="", joints="", forces="", parameters="", extra=""):
    text = f"casmech: 1\nname: m\nparameters:\n  L: 2.0\n  k: 10\n{parameters}bodies:\n"
    text += body("bar", "velocity: [1, 0, 0]") + bodies
    text += f"joints:\n{joints}" if joints else ""
    text += f"forces:\n{forces}" if forces else ""
    return load_model_text(text + extra, "m.yaml")


def findings(**parts):
    with pytest.raises(ModelError) as caught:
        model(**parts)
    return caught.value.diagnostics


AXIS, ANGLE = np.array([1.0, 2.0, 3.0]), 2.0
R = rodrigues(AXIS, ANGLE)
U = AXIS / np.linalg.norm(AXIS)
P = np.concatenate([[math.cos(ANGLE / 2)], math.sin(ANGLE / 2) * U])


def test_orientation_forms_give_the_same_euler_parameters():
    x, y, z = R.T  # the body axes in the global frame
    forms = {
        "ep": f"euler_parameters: {vec(P)}",
        "aa": f"axis_angle: {{axis: {vec(2 * AXIS)}, angle: {ANGLE!r}}}",
        "mat": f"matrix: [{vec(R[0])}, {vec(R[1])}, {vec(R[2])}]",
        "xy": f"x_axis: {vec(3 * x)}, y_axis: {vec(y + 0.5 * x)}",  # scaled, then sheared
        "yz": f"y_axis: {vec(y)}, z_axis: {vec(2 * z - y)}",
        "xz": f"x_axis: {vec(x)}, z_axis: {vec(z + 4 * x)}",
    }
    bodies = "".join(body(name, f"orientation: {{{form}}}") for name, form in forms.items())
    resolved = {b.name: b.euler_parameters for b in model(bodies).bodies}
    for name in forms:
        np.testing.assert_allclose(resolved[name], P, **ROT, err_msg=name)
        np.testing.assert_allclose(a_of_p(resolved[name]), R, **ROT, err_msg=name)
    np.testing.assert_allclose(resolved["bar"], [1, 0, 0, 0], rtol=0, atol=0)  # default: exact


@pytest.mark.parametrize(
    ("axis", "angle"),
    [([1, 0, 0], 0.0), ([1, 0, 0], math.pi), ([0, 1, 0], math.pi), ([0, 0, 1], math.pi),
     ([1, 1, 1], 3.0), ([1, -2, 0.5], -2.5), ([0, 0, 1], 2 * math.pi - 1e-3)],
)  # fmt: skip
def test_shepperd_on_every_branch(axis, angle):
    """Each case makes a different diagonal entry of the 4x4 table the largest."""
    p = from_matrix(rodrigues(axis, angle))
    assert p[0] >= 0
    np.testing.assert_allclose(np.linalg.norm(p), 1.0, rtol=0, atol=1e-15)  # normalised last
    np.testing.assert_allclose(a_of_p(p), rodrigues(axis, angle), **ROT)
    np.testing.assert_allclose(rotation_matrix(p), a_of_p(p), **ROT)


JOINTS = """\
  - {name: pin, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 0, 2],
     driver: {angle: "pi/4 * cos(2*t)"}}
  - {name: ball, type: spherical, body_i: bar, body_j: b2, at: [0, 1, 0]}
  - {name: cross, type: universal, body_i: bar, body_j: b2, at: [0, 1, 0], axis_i: [3, 0, 0],
     axis_j: [0, 1, 0]}
  - {name: cyl, type: cylindrical, body_i: bar, body_j: b2, at: [0, 1, 0], axis: [1, 0, 0],
     driver: {angle: t, displacement: 0.1*t}}
  - {name: slide, type: translational, body_i: bar, body_j: b2, at: [0, 1, 0], axis: [1, 1, 0],
     driver: {displacement: L * t}}
  - {name: weld, type: fixed, body_i: bar, body_j: b2, at: [0, 1, 0]}
  - {name: rod, type: distance, body_i: bar, body_j: b2, at_i: [0, 1, 0], at_j: [0, 4, 4]}
  - {name: rod2, type: distance, body_i: bar, body_j: b2, at_i: [0, 1, 0], at_j: [0, 4, 4],
     length: 2 * L}
  - {name: rs, type: revolute_spherical, body_i: bar, body_j: b2, at: [0, 1, 0],
     axis: [0, 0, 1], at_j: [1, 1, 0]}
  - {name: plane, type: planar, body_i: ground, body_j: b2, at: [0, 1, 0], axis: [0, 0, -1]}
  - {name: c1, type: dp1, body_i: ground, a_i: [0, 0, 2], body_j: bar, a_j: [1, 0, 0]}
  - {name: c2, type: dp2, body_i: ground, a_i: [1, 0, 0], s_i: [0, 0, 0], body_j: bar,
     s_j: [-1, 0, 0], f: 0.5}
  - {name: c3, type: d, body_i: ground, s_i: [0, 0, 0], body_j: bar, s_j: [-1, 0, 0], f: "4"}
  - {name: c4, type: cd, c: [1, 0, 0], body_i: ground, s_i: [0, 0, 0], body_j: bar,
     s_j: [-1, 0, 0], f: L * sin(t)}
"""
FORCES = """\
  - {name: spring, type: tsda, body_i: ground, at_i: [0, 0, 0], body_j: bar, at_j: [0, 3, 4],
     stiffness: k, damping: 1, actuator: "-0.5 * length_dot + t - length"}
  - {name: spring2, type: tsda, body_i: ground, at_i: [0, 0, 0], body_j: bar, at_j: [0, 3, 4],
     free_length: L}
  - {name: torsion, type: rsda, joint: pin, stiffness: 3, free_angle: 0.1,
     actuator: "-angle - 2 * angle_dot"}
  - {name: push, type: force, body: b2, value: [0, "sin(t)", 0]}
  - {name: push2, type: force, body: b2, at: [1, 1, 1], value: [1, 2, 3], frame: body}
  - {name: twist, type: torque, body: b2, value: [0, 0, k]}
"""
B2 = """\
  - name: b2
    mass: 7800 * L * 0.05**2
    inertia: [1, 2, 2.5, 0.1, -0.2, 0.3]
    position: [1, 2, 3]
    angular_velocity: [0, 0, 1]
    geometry:
      - {box: [L, 0.1, 0.1]}
      - {cylinder: {radius: 0.05, length: L, axis: x}, offset: [0.1, 0, 0]}
      - {sphere: 0.05, orientation: {axis_angle: {axis: [0, 0, 1], angle: pi}}}
      - {mesh: part.stl, scale: 0.001}
"""


@pytest.fixture(scope="module")
def everything():
    return model(B2, JOINTS, FORCES, extra="analysis: {type: kinematics, formulation: romega}\n")


def test_bodies(everything):
    bar, b2 = everything.bodies
    assert b2.mass == pytest.approx(39.0, rel=1e-15)  # 7800 * 2 * 0.0025 in floating point
    np.testing.assert_array_equal(
        b2.inertia, [[1, 0.1, -0.2], [0.1, 2, 0.3], [-0.2, 0.3, 2.5]]
    )  # the 6-form fills the matrix as written: exact
    np.testing.assert_array_equal(bar.velocity, [1, 0, 0])
    np.testing.assert_array_equal(bar.angular_velocity, [0, 0, 0])
    np.testing.assert_array_equal(b2.angular_velocity, [0, 0, 1])
    box, cylinder, sphere, mesh = b2.geometry
    np.testing.assert_array_equal(box["size"], [2, 0.1, 0.1])
    assert (cylinder["axis"], cylinder["radius"], cylinder["length"]) == ("x", 0.05, 2.0)
    np.testing.assert_array_equal(cylinder["offset"], [0.1, 0, 0])
    np.testing.assert_allclose(sphere["euler_parameters"], [0, 0, 0, 1], **ROT)
    assert (mesh["file"], mesh["scale"]) == ("part.stl", 0.001)
    np.testing.assert_array_equal(everything.gravity, [0, 0, -9.81])
    assert everything.parameters == {"L": 2.0, "k": 10.0}


def test_joint_vectors(everything):
    joints = {joint.name: joint for joint in everything.joints}
    assert [joint.type for joint in everything.joints][:10] == [
        "revolute", "spherical", "universal", "cylindrical", "translational", "fixed",
        "distance", "distance", "revolute_spherical", "planar",
    ]  # fmt: skip
    # composite axes are normalised (global); basic vectors stay as written (body frames)
    np.testing.assert_array_equal(joints["pin"].vectors["axis"], [0, 0, 1])
    np.testing.assert_array_equal(joints["cross"].vectors["axis_i"], [1, 0, 0])
    np.testing.assert_allclose(
        joints["slide"].vectors["axis"], [0.5**0.5, 0.5**0.5, 0], rtol=1e-15, atol=0
    )  # one division by sqrt(2)
    np.testing.assert_array_equal(joints["c1"].vectors["a_i"], [0, 0, 2])
    assert set(joints["c4"].vectors) == {"c", "s_i", "s_j"}
    assert set(joints["rs"].vectors) == {"at", "axis", "at_j"}
    assert joints["rod"].length == 5.0  # |(0, 3, 4)|: exact
    assert joints["rod2"].length == 4.0
    assert joints["pin"].length is None


def test_functions_of_time(everything):
    joints = {joint.name: joint for joint in everything.joints}
    pin, cyl, slide = joints["pin"], joints["cyl"], joints["slide"]
    assert (pin.f, pin.drivers.get("displacement")) == (None, None)
    # evaluation of cos/sin at one point: a few ulps
    np.testing.assert_allclose(pin.drivers["angle"].value(t=0.3), math.pi / 4 * math.cos(0.6),
                               rtol=1e-15, atol=0)  # fmt: skip
    assert (cyl.drivers["angle"].value(t=2.0), cyl.drivers["displacement"].value(t=2.0)) == \
        (2.0, 0.2)
    assert slide.drivers["displacement"].value(t=3.0) == 6.0
    assert joints["c1"].f.is_zero and not joints["c2"].f.is_zero
    t = casadi.SX.sym("t")
    f = casadi.Function("f", [t], [joints["c4"].f.casadi(t=t)])
    np.testing.assert_allclose(float(f(0.5)), 2 * math.sin(0.5), rtol=1e-15, atol=0)
    assert joints["c4"].f.variables == ("t",)
    assert (pin.drivers["angle"].source.line, pin.drivers["angle"].source.col) == (20, 22)


def test_forces(everything):
    spring, spring2, torsion, push, push2, twist = everything.forces
    assert (spring.body_i, spring.body_j, spring.stiffness, spring.damping) == (
        "ground",
        "bar",
        10,
        1,
    )
    assert (spring.free_length, spring2.free_length) == (5.0, 2.0)  # default: the initial length
    assert spring.actuator.variables == ("t", "length", "length_dot")
    assert spring.actuator.value(t=1.0, length=2.0, length_dot=4.0) == -3.0
    assert (torsion.joint, torsion.body_i, torsion.body_j) == ("pin", "ground", "bar")
    assert (torsion.free_angle, torsion.stiffness) == (0.1, 3.0)
    assert torsion.actuator.value(t=0.0, angle=1.0, angle_dot=1.0) == -3.0
    np.testing.assert_array_equal(push.vectors["at"], [1, 2, 3])  # default: the CM
    np.testing.assert_array_equal(push2.vectors["at"], [1, 1, 1])
    assert (push.frame, push2.frame) == ("global", "body")
    assert [component.value(t=math.pi / 2) for component in push.value] == [0.0, 1.0, 0.0]
    assert twist.value[2].value(t=0.0) == 10.0 and twist.body == "b2"


def test_sources_and_analysis(everything):
    pin = everything.joints[0]  # line 19 of the file; its driver is on line 20
    assert (pin.source.line, pin.source.col) == (19, 5)
    sources = {key: (pin.sources[key].line, pin.sources[key].col) for key in pin.sources}
    assert {key: sources[key] for key in ("at", "axis", "driver", "driver.angle")} == {
        "at": (19, 62), "axis": (19, 77), "driver": (20, 6), "driver.angle": (20, 15),
    }  # fmt: skip
    b2 = everything.bodies[1]
    assert (b2.source.line, b2.source.col) == (8, 5)
    analysis = everything.analysis
    # kinematics has no formulation: the key the file wrote is kept for a dynamics run of it
    assert (analysis.type, dict(analysis.written)["formulation"]) == ("kinematics", "romega")
    assert (analysis.t_end, analysis.output_step, analysis.rtol, analysis.atol) == (
        1.0, 0.01, 1e-8, 1e-10,
    )  # fmt: skip


PIN = (
    "  - {name: pin, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 0, 1]}\n"
)


def test_overrides_replace_parameters_and_what_depends_on_them():
    text = "casmech: 1\nname: m\nparameters:\n  L: 2.0\n  m: 3 * L\nbodies:\n"
    text += body("bar", "velocity: [0, 0, 0]").replace("mass: 1", "mass: m")
    resolved = load_model_text(text, overrides={"L": "5", "m": "L**2"})
    assert resolved.parameters == {"L": 5.0, "m": 25.0}
    assert resolved.bodies[0].mass == 25.0
    with pytest.raises(ModelError) as caught:
        load_model_text(text, overrides={"Lx": "1", "L": "2 +", "m": "q"})
    found = [(d.code, d.path, d.source, d.hint) for d in caught.value.diagnostics]
    assert found == [
        ("E300", "--set Lx", None, "did you mean 'L'?"),
        ("E200", "--set L", None, None),
        ("E201", "--set m", None, None),
    ]
    assert str(caught.value).startswith("error[E300] --set Lx: unknown parameter 'Lx'")


def test_parameters_are_evaluated_in_order():
    [diagnostic] = findings(parameters="  a: b + 1\n  b: 2\n")
    assert (diagnostic.code, diagnostic.path, diagnostic.source.col) == ("E201", "parameters.a", 6)
    assert diagnostic.hint == "parameters are evaluated in order; 'b' is defined at line 7"
    [diagnostic] = findings(parameters="  a: a + 1\n")
    assert diagnostic.hint.endswith("line 6")


def test_failed_parameters_are_not_reported_again():
    found = findings(parameters="  a: 1/0\n  b: 2 * a\n", bodies=body("b2", "velocity: [a, 0, 0]"))
    assert [(d.code, d.path) for d in found] == [("E204", "parameters.a")]


@pytest.mark.parametrize(
    ("name", "code"), [("pi", "E302"), ("t", "E302"), ("sqrt", "E302"), ("my-p", "E303")]
)
def test_parameter_names(name, code):
    [diagnostic] = findings(parameters=f"  {name}: 1\n")
    assert (diagnostic.code, diagnostic.source.line, diagnostic.source.col) == (code, 6, 3)


def test_time_and_variables_only_where_allowed():
    ok = "  - {name: d, type: d, body_i: ground, s_i: [0, 0, 0], body_j: bar, s_j: [1, 0, 0],"
    found = findings(
        joints=PIN.replace("axis: [0, 0, 1]}", "axis: [0, 0, 1], driver: {angle: length}}")
        + ok
        + " f: 1 + t}\n",
        forces="  - {name: r, type: rsda, joint: pin, stiffness: 2 * t, actuator: length}\n",
    )
    assert [(d.code, d.path, d.source.col) for d in found] == [
        ("E201", "joints[0].driver.angle", 110),
        ("E202", "forces[0].stiffness", 54),
        ("E201", "forces[0].actuator", 67),
    ]
    assert found[1].hint.startswith("functions of time are allowed in: joint f")


def test_non_finite_at_time_zero():
    [diagnostic] = findings(
        joints=PIN.replace("axis: [0, 0, 1]}", "axis: [0, 0, 1], driver: {angle: 1/t}}")
    )
    assert diagnostic.code == "E204"
    assert diagnostic.message == "'1/t' evaluates to inf at t = 0"


def test_references():
    found = findings(
        joints=PIN.replace("body_j: bar", "body_j: baar"),
        forces="  - {name: r, type: rsda, joint: pinn}\n"
        "  - {name: s, type: rsda, joint: ball}\n"
        "  - {name: f, type: force, body: ground, value: [0, 0, 1]}\n"
        "  - {name: k, type: tsda, body_i: bar, at_i: [0, 0, 0], body_j: bar, at_j: [1, 0, 0]}\n",
        bodies="",
        extra="",
    )
    assert [(d.code, d.path, d.hint) for d in found] == [
        ("E300", "joints[0].body_j", "did you mean 'bar'?"),
        ("E300", "forces[0].joint", "did you mean 'pin'?"),
        ("E300", "forces[1].joint", None),
        ("E300", "forces[2].body", None),
        ("E304", "forces[3].body_j", None),
    ]


def test_rsda_needs_a_revolute_or_cylindrical_joint():
    ball = "  - {name: ball, type: spherical, body_i: ground, body_j: bar, at: [0, 0, 0]}\n"
    [diagnostic] = findings(joints=ball, forces="  - {name: r, type: rsda, joint: ball}\n")
    assert (diagnostic.code, diagnostic.path, diagnostic.got) == (
        "E103", "forces[0].joint", "'ball' is spherical",
    )  # fmt: skip


def test_driver_keys_by_joint_type():
    joints = PIN.replace("axis: [0, 0, 1]}", "axis: [0, 0, 1], driver: {displacement: t}}")
    joints += "  - {name: ball, type: spherical, body_i: ground, body_j: bar, at: [0, 0, 0],"
    joints += " driver: {angle: t}}\n"
    found = findings(joints=joints)
    assert [(d.code, d.path) for d in found] == [
        ("E408", "joints[0].driver.displacement"),
        ("E408", "joints[1].driver.angle"),
    ]
    assert found[1].hint == "allowed on revolute, cylindrical and screw joints"


def test_joint_geometry_checks():
    joints = (
        "  - {name: a, type: distance, body_i: ground, body_j: bar, at_i: [1, 0, 0],"
        " at_j: [1, 0, 0]}\n"
        "  - {name: b, type: distance, body_i: ground, body_j: bar, at_i: [0, 0, 0],"
        " at_j: [1, 0, 0], length: 0}\n"
        "  - {name: c, type: revolute_spherical, body_i: ground, body_j: bar, at: [0, 0, 0],"
        " axis: [0, 0, 1], at_j: [0, 0, 0]}\n"
        "  - {name: d, type: revolute_spherical, body_i: ground, body_j: bar, at: [0, 0, 0],"
        " axis: [0, 0, 1], at_j: [1, 0, 0.01]}\n"
        "  - {name: e, type: dp1, body_i: ground, a_i: [0, 0, 0], body_j: bar, a_j: [1, 0, 0]}\n"
    )
    found = findings(joints=joints)
    assert [(d.code, d.path) for d in found] == [
        ("E404", "joints[0].at_j"),
        ("E404", "joints[1].length"),
        ("E404", "joints[2].at_j"),
        ("E405", "joints[3].at_j"),
        ("E404", "joints[4].a_i"),
    ]
    assert found[0].hint == "use a spherical joint for coincident points"


def test_body_checks_at_their_limits():
    near_unit = f"euler_parameters: {vec([1, 0, 0, 1e-5])}"  # norm - 1 = 5e-11 < 1e-9
    bodies = body("b1", f"orientation: {{{near_unit}}}")
    bodies += body("b2", "velocity: [0, 0, 0]", inertia="[1, 1, 2]")  # a + b = c: a flat plate
    p = model(bodies).bodies[1].euler_parameters
    np.testing.assert_allclose(np.linalg.norm(p), 1.0, rtol=0, atol=1e-15)  # normalised
    bodies = body("b1", "orientation: {x_axis: [1, 0, 0], y_axis: [2, 0, 0]}")
    bodies += body("b2", "orientation: {y_axis: [0, 1, 0], x_axis: [0, 0, 0]}")
    bodies += body("b3", "orientation: {axis_angle: {axis: [0, 0, 0], angle: 1}}")
    bodies += body("b4", "orientation: {}")
    bodies += body("b5", "orientation: {z_axis: [0, 0, 1]}")
    bodies += body("b6", "velocity: [0, 0, 0]", inertia="[[1, 0, 0], [0.5, 1, 0], [0, 0, 1]]")
    found = findings(bodies=bodies)
    assert [(d.code, d.path) for d in found] == [
        ("E405", "bodies[1].orientation.y_axis"),
        ("E404", "bodies[2].orientation.x_axis"),
        ("E404", "bodies[3].orientation.axis_angle.axis"),
        ("E407", "bodies[4].orientation"),
        ("E407", "bodies[5].orientation"),
        ("E401", "bodies[6].inertia"),
    ]
    assert found[0].message == "x_axis and y_axis are parallel"


def test_yaml_strings_that_look_like_numbers_are_numbers():
    resolved = model(parameters="  small: 1e-3\n  big: 2E+3\n  neg: -.5e1\n")
    assert {k: resolved.parameters[k] for k in ("small", "big", "neg")} == {
        "small": 1e-3, "big": 2000.0, "neg": -5.0,
    }  # fmt: skip


def test_euler_parameter_hint_shows_the_normalised_vector():
    [diagnostic] = findings(bodies=body("b", "orientation: {euler_parameters: [1, 0, 0, 1]}"))
    assert diagnostic.code == "E403"
    assert diagnostic.hint == "normalised: [0.707106781187, 0, 0, 0.707106781187]"


@pytest.mark.parametrize(("written", "code", "words"), [
    ("1" + "0" * 400, "E204", "number too large"),  # an int beyond float: no number
    (".inf", "E204", "evaluates to inf"),
    (".nan", "E204", "evaluates to nan"),
    ("2.0e+6", "E411", "a position or length of magnitude 2e+06 m is implausible"),
])
def test_a_plain_number_that_is_no_usable_number_is_located(written, code, words):
    """Plain numbers (YAML ints and floats) are checked as expressions are: too large for a
    float, not finite, implausible for their key, each reported where it is written."""
    from tests.texts import pendulum

    text = pendulum().replace("position: [0, 0, -1]", f"position: [0, {written}, -1]")
    with pytest.raises(ModelError) as caught:
        load_model_text(text, "m.yaml")
    (found,) = caught.value.diagnostics
    column = text.splitlines()[3].index(f"[0, {written}") + 5  # 1-based, after "[0, "
    assert (found.code, found.path, found.source.line, found.source.col) == \
        (code, "bodies[0].position[1]", 4, column)
    assert words in found.message
