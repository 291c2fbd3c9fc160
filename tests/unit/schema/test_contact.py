"""Contact entries and joint limits (schema/contact.py): geometry taken from the bodies'
`geometry`, the normal law's one form, and located errors for bad fields."""

from __future__ import annotations

import numpy as np
import pytest

from casmech.errors import ModelError
from casmech.schema import load_model_text

HEAD = """casmech: 1
name: m
bodies:
  - name: ball
    mass: 1
    inertia: [1, 1, 1]
    position: [1, 2, 3]
    orientation: {axis_angle: {axis: [0, 0, 1], angle: 1.5707963267948966}}
    geometry:
      - {sphere: 0.2, offset: [0.1, 0, 0]}
      - {box: [0.4, 0.2, 0.1], offset: [0, 0, -0.5]}
      - {cylinder: {radius: 0.05, length: 0.6, axis: x}}
  - {name: plain, mass: 1, inertia: [1, 1, 1], position: [0, 0, 5]}
"""


def load(forces: str = "", joints: str = ""):
    text = HEAD + (f"joints:\n{joints}" if joints else "") + f"forces:\n{forces}"
    return load_model_text(text, "m.yaml")


def findings(forces: str = "", joints: str = "") -> list[tuple]:
    with pytest.raises(ModelError) as caught:
        load(forces, joints)
    return [(d.code, d.path, d.source.line, d.source.col) for d in caught.value.diagnostics]


LAW = "normal: {stiffness: 1e5}"


def test_shapes_come_from_the_bodys_geometry_in_global_terms():
    model = load(f"""  - {{name: s, type: sphere_plane, body_j: ball, {LAW}}}
  - {{name: b, type: points_plane, body_j: ball, {LAW}}}
  - {{name: c, type: capsule_plane, body_j: ball, {LAW}}}
""")
    s, b, c = model.forces
    # the body is turned 90 degrees about z: body x is global y (exact to rounding)
    tight = {"rtol": 0, "atol": 1e-12}
    assert s.params["radius"] == 0.2
    np.testing.assert_allclose(s.vectors["center"], [1, 2.1, 3], **tight)
    corners = b.vectors["points"]
    assert corners.shape == (8, 3)
    np.testing.assert_allclose(corners.min(axis=0), [1 - 0.1, 2 - 0.2, 3 - 0.55], **tight)
    np.testing.assert_allclose(corners.max(axis=0), [1 + 0.1, 2 + 0.2, 3 - 0.45], **tight)
    np.testing.assert_allclose(c.vectors["ends"], [[1, 1.7, 3], [1, 2.3, 3]], **tight)
    assert c.params["radius"] == 0.05
    np.testing.assert_allclose(s.vectors["normal"], [0, 0, 1], **tight)  # the default plane


def test_hunt_crossley_and_linear_in_one_form():
    model = load("""  - {name: h, type: sphere_plane, body_j: ball,
     normal: {stiffness: 1e5, restitution: 0.6, impact_velocity: 2}}
  - {name: l, type: sphere_plane, body_j: ball,
     normal: {law: linear, stiffness: 1e5, damping: 30}, friction: {static: 0.4}}
""")
    h, lin = (f.params for f in model.forces)
    assert (h["stiffness"], h["exponent"], h["damping_exponent"]) == (1e5, 1.5, 1.5)
    # c = k alpha with restitution 0.6 at 2 m/s by the law's own impact relation:
    # alpha e v + ln(1 - alpha e v) = -alpha v + ln(1 + alpha v) (to rounding of the logs)
    a, e = h["damping"] / 1e5 * 2, 0.6
    np.testing.assert_allclose(a * e + np.log1p(-a * e), -a + np.log1p(a), rtol=1e-12, atol=0)
    assert 0.5 < a < 1.0  # the root, not a = 0 (Hunt and Crossley's first order: 0.6)
    assert (lin["exponent"], lin["damping"], lin["damping_exponent"]) == (1.0, 30.0, 0.0)
    # friction defaults: dynamic = static, transition = 2 stiction, stiction 1 mm/s
    assert (lin["mu_s"], lin["mu_d"], lin["v_s"], lin["v_t"]) == (0.4, 0.4, 1e-3, 2e-3)
    assert h["mu_s"] == h["mu_d"] == 0.0  # no friction block: frictionless


def located(text: str, line: int, col: int) -> str:
    """The text a diagnostic points at (1-based line and column of the full model)."""
    return text.splitlines()[line - 1][col - 1:]


@pytest.mark.parametrize(("forces", "expected"), [
    # no sphere on 'plain' and no radius given: at body_j
    (f"  - {{name: s, type: sphere_plane, body_j: plain, {LAW}}}\n",
     ("E410", "forces[0].body_j", "plain")),
    (f"  - {{name: s, type: points_plane, body_j: plain, {LAW}}}\n",
     ("E410", "forces[0].body_j", "plain")),
    (f"  - {{name: s, type: sphere_sphere, body_i: plain, body_j: ball, {LAW}}}\n",
     ("E410", "forces[0].body_i", "plain")),
    ("  - {name: s, type: sphere_plane, body_j: ball, normal: {stiffness: -1}}\n",
     ("E103", "forces[0].normal.stiffness", "-1")),
    ("  - {name: s, type: sphere_plane, body_j: ball,\n"
     "     normal: {stiffness: 1, restitution: 1.5}}\n",
     ("E103", "forces[0].normal.restitution", "1.5")),
    ("  - {name: s, type: sphere_plane, body_j: ball,\n"
     "     normal: {stiffness: 1, damping: 3}}\n",
     ("E103", "forces[0].normal.damping", "3")),
    ("  - {name: s, type: sphere_plane, body_j: ball,\n"
     "     normal: {law: linear, stiffness: 1, exponent: 2}}\n",
     ("E103", "forces[0].normal.exponent", "2")),
    ("  - {name: s, type: sphere_plane, body_j: ball, normal: {stiffness: 1}, radius: 0}\n",
     ("E103", "forces[0].radius", "0")),
    ("  - {name: s, type: sphere_plane, body_j: ball, normal: {stiffness: 1},\n"
     "     plane: {normal: [0, 0, 0]}}\n",
     ("E404", "forces[0].plane.normal", "[0, 0, 0]")),
    ("  - {name: s, type: sphere_plane, body_j: ball, normal: {stiffness: 1},\n"
     "     friction: {static: 0.5, stiction_velocity: 1e-3, transition_velocity: 1e-4}}\n",
     ("E103", "forces[0].friction.transition_velocity", "1e-4")),
    ("  - {name: s, type: sphere_plane, body_j: ball, normal: {stiffness: 1},\n"
     "     friction: {static: -0.5}}\n",
     ("E103", "forces[0].friction.static", "-0.5")),
    ("  - {name: s, type: sphere_plane, body_j: ball, normal: {stiffness: 1},\n"
     "     friction: {static: 0.5, model: coulomb}}\n",
     ("E103", "forces[0].friction.model", "coulomb")),
    ("  - {name: s, type: sphere_plane, body_j: ball, normal: {stiffness: 1},\n"
     "     friction: {static: 0.5, model: exact, stiction_velocity: 1e-3}}\n",
     ("E103", "forces[0].friction.stiction_velocity", "1e-3")),
    ("  - {name: s, type: sphere_plane, body_i: ball, body_j: ball, normal: {stiffness: 1}}\n",
     ("E304", "forces[0].body_j", "ball")),
    ("  - {name: s, type: capsule_plane, body_j: ball, normal: {stiffness: 1},\n"
     "     ends: [[0, 0, 0], [0, 0, 0]]}\n",
     ("E410", "forces[0].ends", "[[0, 0, 0]")),
    ("  - {name: s, type: points_plane, body_j: ball, normal: {stiffness: 1}, points: []}\n",
     ("E103", "forces[0].points", "[]")),
    ("  - {name: s, type: sphere_plane, body_j: bal, normal: {stiffness: 1}}\n",
     ("E300", "forces[0].body_j", "bal")),
])
def test_bad_contact_fields_are_located(forces, expected):
    code, path, text = expected
    ((found_code, found_path, line, col),) = findings(forces)
    assert (found_code, found_path) == (code, path)
    assert located(HEAD + "forces:\n" + forces, line, col).startswith(text)


JOINT = "  - {{name: pin, type: {type}, body_i: ground, body_j: plain, at: [0, 0, 5], " \
        "axis: [0, 0, 1], limit: {limit}}}\n"


@pytest.mark.parametrize(("joint", "limit", "expected"), [
    ("revolute", "{lower: 1, upper: -1, stiffness: 10}", ("E103", "joints[0].limit.upper")),
    ("revolute", "{stiffness: 10}", ("E100", "joints[0].limit")),
    ("translational", "{lower: 0, stiffness: 0}", ("E103", "joints[0].limit.stiffness")),
    ("cylindrical", "{upper: 0, stiffness: 1, damping: -2}", ("E103", "joints[0].limit.damping")),
    ("spherical", "{upper: 0, stiffness: 1}", ("E101", "joints[0].limit")),
])
def test_bad_limits_are_located(joint, limit, expected):
    text = JOINT.format(type=joint, limit=limit)
    if joint == "spherical":
        text = text.replace("axis: [0, 0, 1], ", "")
    found = findings(joints=text)
    assert [(code, path) for code, path, _, _ in found] == [expected]
    assert found[0][2] == 15  # on the joint's line


def test_limit_resolves_with_infinite_missing_bound():
    joints = JOINT.format(type="translational", limit="{upper: 0.3, stiffness: 10}")
    (joint,) = load(joints=joints).joints
    assert joint.limit == {"lower": -np.inf, "upper": 0.3, "stiffness": 10.0, "damping": 0.0}


PLACED = """casmech: 1
name: placed
components:
  tile:
    bodies:
      - {name: ball, mass: 1, inertia: [1, 1, 1], position: [0, 0, 1], geometry: [{sphere: 0.1}]}
      - {name: slab, mass: 1, inertia: [1, 1, 1], position: [0, 0, 0],
         geometry: [{box: [1, 1, 0.1]}]}
    forces:
      - {name: rests, type: sphere_plane, body_i: slab, body_j: ball, normal: {stiffness: 1},
         plane: {at: [0, 0, 0.05], normal: [0, 0, 1]}}
      - {name: corners, type: points_plane, body_j: slab, normal: {stiffness: 1},
         points: [[0.5, 0, 0], [-0.5, 0, 0]]}
instances:
  - {name: t, component: tile, position: [1, 2, 3],
     orientation: {axis_angle: {axis: [1, 0, 0], angle: 1.5707963267948966}}}
"""


def test_an_instance_places_contact_points_and_normals():
    rests, corners = load_model_text(PLACED, "m.yaml").forces
    tight = {"rtol": 0, "atol": 1e-12}  # one rotation by 90 degrees: rounding only
    # x-axis quarter turn: (x, y, z) -> (x, -z, y), then + (1, 2, 3)
    np.testing.assert_allclose(rests.vectors["at"], [1, 1.95, 3], **tight)
    np.testing.assert_allclose(rests.vectors["normal"], [0, -1, 0], **tight)
    np.testing.assert_allclose(rests.vectors["center"], [1, 1, 3], **tight)
    np.testing.assert_allclose(corners.vectors["points"], [[1.5, 2, 3], [0.5, 2, 3]], **tight)
    assert (rests.body_i, rests.body_j) == ("t.slab", "t.ball")
