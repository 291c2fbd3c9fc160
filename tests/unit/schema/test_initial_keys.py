"""`initial:` on a joint type that takes none (basic constraints, distance, couplings: no tree
motion, and not posable as a screw is by its angle): an unknown key, located at the key, with
a hint naming the types that take it."""

import pytest

from casmech.elements.joint_types import REGISTRY, initial_keys
from casmech.errors import ModelError
from casmech.schema import load_model_text

MODEL = """\
casmech: 1
name: initial_keys
bodies:
  - {{name: a, mass: 1, inertia: [1, 1, 1], position: [1, 0, 0]}}
  - {{name: b, mass: 1, inertia: [1, 1, 1], position: [2, 0, 0]}}
joints:
  - {{name: p1, type: revolute, body_i: ground, body_j: a, at: [0, 0, 0], axis: [0, 0, 1]}}
  - {{name: p2, type: revolute, body_i: ground, body_j: b, at: [0, 0, 0], axis: [0, 0, 1]}}
  - name: j
{joint}
    initial: {{angle: 0.3}}
analysis: {{type: dynamics, t_end: 1}}
"""
# joint types whose `motion` is None, each as its keys (indented as a block mapping)
JOINTS = {
    "distance": "type: distance\nbody_i: a\nbody_j: b\nat_i: [1, 0, 0]\nat_j: [2, 0, 0]",
    "revolute_spherical": "type: revolute_spherical\nbody_i: a\nbody_j: b\nat: [1, 0, 0]\n"
                          "axis: [0, 0, 1]\nat_j: [2, 0, 0]",
    "dp1": "type: dp1\nbody_i: a\nbody_j: b\na_i: [1, 0, 0]\na_j: [0, 1, 0]",
    "gear": "type: gear\njoint_i: p1\njoint_j: p2\nratio: 2",
}


def test_the_joint_types_checked_have_no_tree_motion():
    assert all(REGISTRY[kind].motion is None for kind in JOINTS)


@pytest.mark.parametrize("kind", JOINTS)
def test_initial_on_a_joint_without_a_tree_motion_is_a_located_error(kind):
    joint = "\n".join(f"    {line}" for line in JOINTS[kind].splitlines())
    text = MODEL.format(joint=joint)
    line = text.splitlines().index("    initial: {angle: 0.3}") + 1
    with pytest.raises(ModelError) as caught:
        load_model_text(text, "m.yaml")
    [found] = caught.value.diagnostics
    assert (found.code, found.path) == ("E101", "joints[2].initial")
    assert (found.source.line, found.source.col) == (line, 5)
    assert str(caught.value).startswith(f"m.yaml:{line}:5: error[E101] joints[2].initial:")
    takers = [name for name in REGISTRY if initial_keys(name)]
    assert takers and all(name in found.hint for name in takers)
    assert f"a {kind} joint takes no initial values" in found.hint
