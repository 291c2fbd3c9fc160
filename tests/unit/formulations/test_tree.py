"""The spanning tree of the joint formulation (formulations/tree.py)."""

import numpy as np

import casmech
from casmech.formulations import tree as tree_module
from casmech.formulations.joint_system import build
from casmech.formulations.tree import spanning_tree
from casmech.model.ir import GROUND_INDEX
from casmech.model.lower import lower
from tests.conftest import MODELS

FOUR_BAR = MODELS / "four_bar.yaml"


def tree_of(text: str):
    return spanning_tree(lower(casmech.loads(text)))


BARS = """
casmech: 1
name: t
bodies:
  - {name: a, mass: 1, inertia: [1, 1, 1], position: [1, 0, 0]}
  - {name: b, mass: 1, inertia: [1, 1, 1], position: [2, 0, 0]}
  - {name: c, mass: 1, inertia: [1, 1, 1], position: [3, 0, 0]}
  - {name: float, mass: 1, inertia: [1, 1, 1], position: [0, 5, 0]}
  - {name: rider, mass: 1, inertia: [1, 1, 1], position: [0, 6, 0]}
joints:
  - {name: ja, type: revolute, body_i: ground, body_j: a, at: [0, 0, 0], axis: [0, 0, 1]}
  - {name: jb, type: revolute, body_i: b, body_j: a, at: [1.5, 0, 0], axis: [0, 0, 1]}
  - {name: jc, type: spherical, body_i: b, body_j: c, at: [2.5, 0, 0] CUT}
  - {name: loop, type: distance, body_i: ground, body_j: c, at_i: [3, 1, 0], at_j: [3, 0, 0]}
  - {name: ride, type: translational, body_i: float, body_j: rider, at: [0, 5.5, 0],
     axis: [0, 1, 0]}
"""


def test_breadth_first_from_ground_in_file_order():
    tree = tree_of(BARS.replace(" CUT", ""))
    names = [(j.name, j.parent, j.child, j.reversed) for j in tree.joints]
    # ja reaches a from ground; jb reaches b from a (written b -> a: reversed); jc reaches c;
    # the floating body gets a free joint from ground, and its rider follows from it
    assert names == [("ja", GROUND_INDEX, 0, False), ("jb", 0, 1, True), ("jc", 1, 2, False),
                     ("", GROUND_INDEX, 3, False), ("ride", 3, 4, False)]
    assert [j.type for j in tree.joints] == ["revolute", "revolute", "spherical", "free",
                                             "translational"]
    assert [j.name for j in tree.cut] == ["loop"]  # a distance joint has no tree motion


def test_cut_true_keeps_a_joint_out_of_the_tree():
    tree = tree_of(BARS.replace(" CUT", ", cut: true"))
    assert [j.name for j in tree.cut] == ["jc", "loop"]
    # no tree joint reaches c any more: it floats, held by the two cut joints' rows
    assert [(j.name, j.type) for j in tree.joints if j.child == 2] == [("", "free")]


def test_four_bar_cuts_the_joint_that_closes_its_loop():
    tree = spanning_tree(lower(casmech.load(FOUR_BAR)))
    assert len(tree.joints) == 3 and len(tree.cut) == 1
    children = sorted(j.child for j in tree.joints)
    assert children == [0, 1, 2]  # every body once


# bodies posed at rotations: their joints' frames on the bodies carry rounding residues
POSED = """
casmech: 1
name: posed
bodies:
  - {name: a, mass: 1, inertia: [1, 2, 3], position: [0.3, 0.1, 0],
     orientation: {euler_parameters: [0.8597552011148939, 0.5107063678434883, 0, 0]}}
  - {name: b, mass: 2, inertia: [1, 1, 2], position: [0.6, 0.2, 0.1],
     orientation: {euler_parameters: [0.7968437806845068, 0.4733361222407707,
                                      -0.1917652459074863, 0.32282966875510855]}}
joints:
  - {name: ja, type: revolute, body_i: ground, body_j: a, at: [0, 0, 0], axis: [1, 0, 0]}
  - {name: jb, type: revolute, body_i: a, body_j: b, at: [0.5, 0.1, 0], axis: [0, 0, 1]}
"""


def _with_residues(ir, monkeypatch):
    """The tree of `ir` with its frames as placed (no residue made a zero)."""
    with monkeypatch.context() as patch:
        patch.setattr(tree_module, "_without_residues", lambda frame: frame)
        return spanning_tree(ir)


def test_a_frames_rounding_residues_are_zeros(monkeypatch):
    ir = lower(casmech.loads(POSED))
    clean, placed = spanning_tree(ir), _with_residues(ir, monkeypatch)
    residues = 0
    for joint, raw in zip(clean.joints, placed.joints, strict=True):
        for got, frame in ((joint.parent_frame, raw.parent_frame),
                           (joint.child_frame, raw.child_frame)):
            for k, vectors in ((0, 0), (1, None)):  # the axes by column, the point whole
                value = frame[k]
                largest = np.abs(value).max(axis=vectors, keepdims=True)
                residue = (value != 0) & (np.abs(value) <= tree_module.RESIDUE * largest)
                residues += int(residue.sum())
                np.testing.assert_array_equal(got[k], np.where(residue, 0.0, value))
    assert residues > 0  # the posed frames have some (else this test tests nothing)


def test_the_ode_without_residues_is_the_placed_frames_to_roundoff(monkeypatch):
    ir = lower(casmech.loads(POSED))
    clean = build(ir, spanning_tree(ir)).dynamics
    placed = build(ir, _with_residues(ir, monkeypatch)).dynamics
    assert clean.n_instructions() < placed.n_instructions()  # their products folded away
    rng = np.random.default_rng(7)
    for _ in range(5):
        x = rng.uniform(-2, 2, clean.nnz_in(1))
        # frames that differ by residues below 1e-15 of their entries: the same accelerations
        # to round-off
        np.testing.assert_allclose(np.asarray(clean(0.3, x)), np.asarray(placed(0.3, x)),
                                   rtol=1e-12, atol=1e-13)
