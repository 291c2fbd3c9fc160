"""The joint registry (casmech.elements.joint_types): every entry is complete and consistent, so
that a
malformed new entry fails here rather than in some stage that reads it."""

import pytest

from casmech.elements import joint_types
from casmech.elements.joint_types import BUILT_IN, COORDINATES, MOTIONS, JointType
from casmech.elements.primitives import PRIMITIVES

AXES = {"u", "v", "w", "ex", "ey", "ez"}  # always in the joint frame (model/lower.py)


def quantities(entry: JointType) -> set[str]:
    """The joint-frame quantities an entry's YAML keys provide."""
    return {entry.frame[key] for key in entry.vectors if key in entry.frame} | AXES


def rows(entry: JointType):
    return [*entry.rows, *(COORDINATES[c].driver for c in entry.coordinates)]


@pytest.mark.parametrize("entry", BUILT_IN, ids=lambda e: e.name)
def test_rows_are_primitives_on_quantities_the_entry_has(entry):
    for kind, template, _ in rows(entry):
        assert set(template) == set(PRIMITIVES[kind][1])  # the primitive's vector keys
        for value in template.values():
            name, _, side = value.partition("@")
            if entry.basic:
                assert not side and name in entry.vectors
            elif side:  # a quantity in body i's or j's frame
                assert side in ("i", "j") and name in quantities(entry)
            elif entry.constants is not None and name in entry.constants(
                    dict.fromkeys(entry.options, 1.0)):  # from its scalars (a screw's lead)
                assert name not in quantities(entry)
            else:  # used as written: CD's global unit vector c
                assert kind == "cd" and name in ("ex", "ey", "ez")


@pytest.mark.parametrize("entry", BUILT_IN, ids=lambda e: e.name)
def test_reaction_point_arm_and_coordinates_are_known(entry):
    have = set(entry.vectors) if entry.basic else quantities(entry)
    assert entry.reaction_point is None or entry.reaction_point in have
    assert entry.arm is None or set(entry.arm) <= have
    assert set(entry.coordinates) <= set(COORDINATES)
    assert entry.limit is None or entry.limit in entry.coordinates
    assert not (entry.basic and entry.coordinates)  # basic constraints take no driver


@pytest.mark.parametrize("entry", [e for e in BUILT_IN if e.motion], ids=lambda e: e.name)
def test_a_tree_motion_drives_exactly_the_entry_coordinates(entry):
    """The joint formulation prescribes a driver on the coordinate the entry names."""
    assert set(entry.motion.drivers) == set(entry.coordinates)
    assert all(0 <= k < entry.motion.n_q for k in entry.motion.drivers.values())


@pytest.mark.parametrize("entry", [e for e in BUILT_IN if e.couples], ids=lambda e: e.name)
def test_a_coupling_names_coordinates_and_its_output(entry):
    """A coupling has no rows, vectors or coordinates of its own; it reads known coordinates
    and its output is one of its joints; its coefficients are one per joint."""
    couples = entry.couples
    assert not entry.rows and not entry.vectors and not entry.coordinates
    assert set(couples.uses) <= set(COORDINATES) and len(couples.uses) == len(couples.joints)
    values = dict.fromkeys(couples.scalars, 2.0) | {"coefficients": [1.0, 3.0]}
    assert len(couples.coefficients(values)) == (len(couples.joints) or 2)
    assert 0 <= couples.output < (len(couples.joints) or 2)


def test_queries_follow_the_registry():
    assert joint_types.having("angle") == ("revolute", "cylindrical", "screw")
    assert joint_types.having("displacement") == ("translational", "cylindrical", "screw")
    assert set(MOTIONS) == {e.name for e in BUILT_IN if e.motion} | {"free"}
    assert joint_types.attributes("cylindrical") == ["angle", "angle_dot", "displacement",
                                                      "displacement_dot"]
    assert joint_types.attributes("spherical") == ["e0", "e1", "e2", "e3", "wx", "wy", "wz"]
    assert joint_types.attributes("fixed") == []
    assert joint_types.initial_keys("universal") == ("angle_i", "angle_i_dot", "angle_j",
                                                     "angle_j_dot")
    assert joint_types.initial_keys("dp1") == ()
