"""Located errors of the couplings (gear, rack_pinion, coupler, screw): each at its key, with
the code docs/format.md lists for it."""

import pytest

import casmech
from casmech.errors import ModelError

BASE = """casmech: 1
name: e
bodies:
  - {name: d1, mass: 1, inertia: [1, 1, 1], position: [0, 0, 0]}
  - {name: d2, mass: 1, inertia: [1, 1, 1], position: [1, 0, 0]}
joints:
  - {name: p1, type: revolute, body_i: ground, body_j: d1, at: [0, 0, 0], axis: [0, 0, 1]}
  - {name: s2, type: translational, body_i: ground, body_j: d2, at: [1, 0, 0], axis: [1, 0, 0]}
  - {name: c2, type: cylindrical, body_i: d1, body_j: d2, at: [1, 0, 0], axis: [1, 0, 0]}
"""

CASES = [  # (the coupling, code, path, the key it is at, words of the message)
    ("{name: g, type: gear, joint_i: p1, joint_j: s2, ratio: 2}", "E103", "joints[3].joint_j",
     "s2", "'s2' is translational"),
    ("{name: g, type: gear, joint_i: p1, joint_j: p9, ratio: 2}", "E300", "joints[3].joint_j",
     "p9", "unknown joint 'p9'"),
    ("{name: g, type: gear, joint_i: p1, joint_j: c2, ratio: 0}", "E404", "joints[3].ratio",
     "0}", "must not be zero"),
    ("{name: g, type: rack_pinion, joint_i: p1, joint_j: c2.angle, radius: 1}", "E300",
     "joints[3].joint_j", "c2.angle", "unknown joint"),
    ("{name: g, type: rack_pinion, joint_i: p1, joint_j: p1, radius: 1}", "E103",
     "joints[3].joint_j", "p1, radius", "displacement of a translational"),
    ("{name: g, type: coupler, joints: [p1, c2], coefficients: [1, 2]}", "E103",
     "joints[3].joints[1]", "c2]", "write 'c2.angle' or 'c2.displacement'"),
    ("{name: g, type: coupler, joints: [p1, c2.displacement], coefficients: [1]}", "E105",
     "joints[3].coefficients", "[1]", "one coefficient per joint"),
    ("{name: g, type: coupler, joints: [p1], coefficients: [1]}", "E105", "joints[3].joints",
     "[p1]", "2 or 3 joint coordinates"),
    ("{name: g, type: coupler, joints: [p1, s2, c2.angle, c2.displacement], "
     "coefficients: [1, 1, 1, 1]}", "E105", "joints[3].joints", "[p1, s2", "2 or 3"),
    ("{name: g, type: coupler, joints: [p1, p1.angle], coefficients: [1, 2]}", "E301",
     "joints[3].joints[1]", "p1.angle", "coupled twice"),
    ("{name: g, type: coupler, joints: [p1, s2.angle], coefficients: [1, 2]}", "E103",
     "joints[3].joints[1]", "s2.angle", "'s2' is translational"),
    ("{name: g, type: coupler, joints: [p1, s2], coefficients: [1, 0.0]}", "E404",
     "joints[3].coefficients[1]", "0.0", "must not be zero"),
    ("{name: g, type: gear, joint_i: p1, joint_j: c2, ratio: 2 mm}", "E205", "joints[3].ratio",
     "2 mm", "expected a number"),
    ("{name: g, type: rack_pinion, joint_i: p1, joint_j: s2, radius: 2 kg}", "E205",
     "joints[3].radius", "2 kg", "length"),
    ("{name: g, type: screw, body_i: d1, body_j: d2, at: [0, 0, 0], axis: [0, 0, 1], "
     "lead: 0}", "E404", "joints[3].lead", "0}", "must not be zero"),
    ("{name: g, type: screw, body_i: d1, body_j: d2, at: [0, 0, 0], axis: [0, 0, 1], "
     "lead: 3 s}", "E205", "joints[3].lead", "3 s", "length"),
]


@pytest.mark.parametrize(("coupling", "code", "path", "at", "words"), CASES,
                         ids=[case[2] + "-" + case[1] for case in CASES])
def test_a_wrong_coupling_is_a_located_error(coupling, code, path, at, words):
    line = f"  - {coupling}"
    with pytest.raises(ModelError) as caught:
        casmech.loads(BASE + line + "\n")
    text = str(caught.value)
    column = line.index(at) + 1
    assert f"<string>:10:{column}: error[{code}] {path}:" in text, text
    assert words in text


def test_a_screw_without_a_lead_names_the_key():
    line = "  - {name: g, type: screw, body_i: d1, body_j: d2, at: [0, 0, 0], axis: [0, 0, 1]}"
    with pytest.raises(ModelError, match=r"error\[E100\] joints\[3\]\.lead: a screw joint "
                                         r"needs `lead`"):
        casmech.loads(BASE + line + "\n")


def test_a_coupling_may_name_joints_written_after_it():
    text = BASE.replace("joints:\n", "joints:\n  - {name: g, type: gear, joint_i: p1, "
                                     "joint_j: c2, ratio: 2}\n")
    model = casmech.loads(text)
    gear = model.joints[0]
    assert gear.couples == (("p1", "angle"), ("c2", "angle"))
    assert (gear.body_i, gear.body_j) == ("d1", "d2")  # the output joint's bodies


def test_a_screws_initial_takes_its_angle_only():
    """A screw's displacement follows its angle by the lead (docs/format.md, couplings):
    `initial.displacement` is an unknown key, and the hint names the keys it takes."""
    line = ("  - {name: g, type: screw, body_i: d1, body_j: d2, at: [0, 0, 0], axis: [0, 0, 1], "
            "lead: 0.01, initial: {displacement: 0.1}}")
    with pytest.raises(ModelError, match=r"error\[E101\] joints\[3\]\.initial\.displacement: "
                       r"unknown key 'displacement'\n  hint: allowed keys: angle, angle_dot"):
        casmech.loads(BASE + line + "\n")
