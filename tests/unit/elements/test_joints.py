"""Composite joints (casmech.elements.joint_types rows, lowered by model/lower.py) between two FREE
bodies: degrees of freedom, closure at the file's pose, and invariance under the joint's physical
free motions; drivers; redundancy reporting (equations/checks.py).

Geometry: non-trivial orientations of both bodies, the joint point away from both CMs, the axis
along no coordinate axis. Oracle: the kinematics of each joint type (what relative motions it
allows), expressed as finite rigid motions built with Rodrigues' formula and quaternion products.
"""

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pytest

from casmech.elements import joint_types
from casmech.equations import checks
from tests.helpers.equations import (
    compile_model,
    coordinates,
    joint,
    model,
    perpendicular,
    rank,
    rotate_pose,
    scalar,
    stack_q,
    two_free_bodies,
    unit,
)

P = np.array([0.9, 0.1, 0.7])  # joint point; the CMs are near (0.3, -0.2, 1.1), (1.4, 0.6, 0.5)
W = unit([0.3, -0.5, 0.8])  # joint axis
W2 = unit(np.cross(W, [0.2, 0.9, -0.4]))  # universal: axis_j, perpendicular to W
AT_J = P + np.array([0.4, 0.3, -0.5])  # distance: second point
Q = P + 0.6 * perpendicular(W)  # revolute_spherical: sphere centre, |Q - P| . W = 0
EX, EY, EZ = np.eye(3)

Pose = tuple[np.ndarray, np.ndarray]
Motion = Callable[[list[Pose], float], list[Pose]]

# Exact arithmetic with O(1) numbers: Phi at an exact configuration is roundoff, ~1e-15.
CLOSURE = {"rtol": 1e-12, "atol": 1e-12}


def turn_j(axis, point) -> Motion:
    """Body j rotated by s about `axis` through `point`; body i stays."""
    return lambda poses, s: [poses[0], rotate_pose(*poses[1], axis, s, point)]


def slide_j(direction) -> Motion:
    return lambda poses, s: [poses[0], (poses[1][0] + s * np.asarray(direction), poses[1][1])]


LEAD = 0.45  # screw: advance per turn


def screw_j(axis, point, lead) -> Motion:
    """Body j turned by s about `axis` through `point` and slid by lead s / (2 pi) along it."""
    def motion(poses, s):
        r, p = rotate_pose(*poses[1], axis, s, point)
        return [poses[0], (r + lead * s / (2 * np.pi) * np.asarray(axis), p)]
    return motion


def rigid(motion_of_one: Callable[[Pose, float], Pose]) -> Motion:
    """The same rigid motion applied to both bodies (every joint allows it)."""
    return lambda poses, s: [motion_of_one(pose, s) for pose in poses]


CENTRE = np.array([-0.4, 0.8, 0.2])
RIGID_MOTIONS: list[Motion] = (
    [rigid(lambda pose, s, e=e: (pose[0] + s * e, pose[1])) for e in (EX, EY, EZ)]
    + [rigid(lambda pose, s, e=e: rotate_pose(*pose, e, s, CENTRE)) for e in (EX, EY, EZ)])


@dataclass
class Case:
    vectors: dict
    removed: int  # rows the joint removes (independent constraint equations)
    free: list[Motion] = field(default_factory=list)  # relative motions the joint allows
    options: dict = field(default_factory=dict)  # its scalar options (a screw's lead)


CASES: dict[str, Case] = {
    "spherical": Case({"at": P}, 3, [turn_j(e, P) for e in (EX, EY, EZ)]),
    "universal": Case({"at": P, "axis_i": W, "axis_j": W2}, 4, [turn_j(W, P), turn_j(W2, P)]),
    "revolute": Case({"at": P, "axis": W}, 5, [turn_j(W, P)]),
    "cylindrical": Case({"at": P, "axis": W}, 4, [turn_j(W, P), slide_j(W)]),
    "translational": Case({"at": P, "axis": W}, 5, [slide_j(W)]),
    "fixed": Case({"at": P, "axis": W}, 6, []),
    # j turns about any axis through either end point (5 independent relative motions).
    "distance": Case({"at_i": P, "at_j": AT_J}, 1,
                     [turn_j(e, point) for point in (P, AT_J) for e in (EX, EY, EZ)]),
    # Q circles about the axis through P; j turns about any axis through Q.
    "revolute_spherical": Case({"at": P, "at_j": Q, "axis": W}, 2,
                               [turn_j(W, P)] + [turn_j(e, Q) for e in (EX, EY, EZ)]),
    # the cylindrical joint's motions tied: one turn advances LEAD
    "screw": Case({"at": P, "axis": W}, 5, [screw_j(W, P, LEAD)], {"lead": LEAD}),
    "planar": Case({"at": P, "axis": W}, 3,
                   [slide_j(perpendicular(W)), slide_j(np.cross(W, perpendicular(W))),
                    turn_j(W, P), turn_j(W, P + 0.5 * perpendicular(W))]),
}


def test_every_joint_type_has_a_case():
    assert set(CASES) == {e.name for e in joint_types.BUILT_IN
                          if not e.basic and e.couples is None}  # couplings: no two bodies


class Mechanism:
    """Two free bodies and one joint, compiled; q at the file's pose."""

    def __init__(self, rng, joint_type: str, **extra):
        self.bodies = two_free_bodies(rng)
        case = CASES[joint_type]
        options = {"options": case.options} if case.options else {}
        j = joint("j", joint_type, "b1", "b2", **case.vectors, **options, **extra)
        self.functions = compile_model(model(self.bodies, [j]))
        self.poses = [(b.position, b.euler_parameters) for b in self.bodies]
        self.q0 = coordinates(self.bodies)

    def phi(self, q, t=0.0):
        return self.functions.vector("phi", t, q)

    def phi_q(self, q, t=0.0):
        return self.functions.matrix("phi_q", t, q)

    def moved(self, motion: Motion, s: float) -> np.ndarray:
        return stack_q(motion(self.poses, s))


@pytest.fixture(params=sorted(CASES))
def joint_type(request):
    return request.param


def test_closed_at_the_file_pose(joint_type, rng):
    m = Mechanism(rng, joint_type)
    np.testing.assert_allclose(m.phi(m.q0), 0.0, **CLOSURE)


def test_degrees_of_freedom(joint_type, rng):
    """DOF = 14 - rank(Phi_q incl. the 2 normalization rows) = 12 - rows removed, with a clean
    gap in the singular values; checks.structure agrees and finds nothing redundant."""
    m = Mechanism(rng, joint_type)
    expected = 12 - CASES[joint_type].removed
    phi_q = m.phi_q(m.q0)
    s = np.linalg.svd(phi_q, compute_uv=False)
    assert phi_q.shape == (CASES[joint_type].removed + 2, 14)
    assert 14 - rank(phi_q) == expected
    assert s[-1] > 1e-3 * s[0]  # full row rank, far from singular
    structure = checks.structure(m.functions, 0.0, m.q0)
    assert structure.dof == expected
    assert structure.nominal_dof == expected
    assert structure.redundant == ()


def test_free_motions_keep_the_joint_closed(joint_type, rng):
    """Finite (0.3 rad / 0.3 m) free motions of the joint and rigid motions of the pair."""
    m = Mechanism(rng, joint_type)
    for motion in CASES[joint_type].free + RIGID_MOTIONS:
        np.testing.assert_allclose(m.phi(m.moved(motion, 0.3)), 0.0, **CLOSURE)


def test_free_motions_span_the_null_space(joint_type, rng):
    """The velocities of the free motions are in the null space of Phi_q, and they span it:
    the joint allows exactly the motions its type describes, no more."""
    m = Mechanism(rng, joint_type)
    h = 1e-6
    velocities = np.column_stack([(m.moved(mo, h) - m.moved(mo, -h)) / (2 * h)
                                  for mo in CASES[joint_type].free + RIGID_MOTIONS])
    # Central differences of smooth O(1) motions: truncation h^2 ~ 1e-12, roundoff eps / h
    # ~ 1e-10 per velocity entry, times |Phi_q| ~ 10.
    np.testing.assert_allclose(m.phi_q(m.q0) @ velocities, 0.0, rtol=1e-8, atol=1e-8)
    assert rank(velocities, relative=1e-6) == 12 - CASES[joint_type].removed


# --- drivers -------------------------------------------------------------------------------------

DRIVEN = {  # joint type, driver keys -> motions producing the driven pose at f = 0.7
    ("revolute", ("driver_angle",)): [turn_j(W, P)],
    ("cylindrical", ("driver_angle",)): [turn_j(W, P)],
    ("cylindrical", ("driver_displacement",)): [slide_j(W)],
    ("cylindrical", ("driver_angle", "driver_displacement")): [turn_j(W, P), slide_j(W)],
    ("translational", ("driver_displacement",)): [slide_j(W)],
}


@pytest.mark.parametrize(("joint_type", "drivers"), sorted(DRIVEN))
def test_driver(joint_type, drivers, rng):
    """f(t) = 0.7 t at t = 1: body j turned by 0.7 rad about the axis through P (angle) and/or
    slid by 0.7 along the axis (displacement) closes every row; each driver removes one DOF."""
    m = Mechanism(rng, joint_type, **{key: scalar("0.7*t") for key in drivers})
    poses = m.poses
    for motion in DRIVEN[joint_type, drivers]:
        poses = motion(poses, 0.7)
    q = stack_q(poses)
    np.testing.assert_allclose(m.phi(q, t=1.0), 0.0, **CLOSURE)
    # Not closed at the undriven pose: the driver rows see the 0.7 offset.
    assert np.all(np.abs(m.phi(m.q0, t=1.0)[-2 - len(drivers):-2]) > 0.5)
    undriven = 12 - CASES[joint_type].removed
    assert 14 - rank(m.phi_q(q, t=1.0)) == undriven - len(drivers)
    assert checks.structure(m.functions, 1.0, q).dof == undriven - len(drivers)


# --- redundancy ----------------------------------------------------------------------------------

def two_revolutes(rng, second_point):
    bodies = two_free_bodies(rng)
    pair = [joint("first", "revolute", "b1", "b2", at=P, axis=W),
            joint("second", "revolute", "b1", "b2", at=second_point, axis=W)]
    functions = compile_model(model(bodies, pair))
    return checks.structure(functions, 0.0, coordinates(bodies))


@pytest.mark.parametrize("offset", [0.0, 0.6], ids=["same_point", "other_point_on_axis"])
def test_redundant_revolute_is_reported_by_name(offset, rng):
    """A second revolute about the same axis (at the same point, or at another point of the
    axis) adds no constraint: its 5 rows are redundant and reported under its name, the DOF stays
    that of one revolute (7).

    The other_point_on_axis case FAILS with the current checks.structure (reported bug): the
    greedy scan runs in row order with the normalization rows LAST, and the second joint's rows
    are only dependent on the first joint's rows TOGETHER WITH the normalization rows, so the
    scan reports "p^T p - 1 of 'b1'" / "of 'b2'" as redundant instead of joint 'second' rows.
    """
    structure = two_revolutes(rng, P + offset * W)
    assert structure.dof == 7
    assert structure.nominal_dof == 2  # the Gruebler count: 12 - 10 rows
    assert [(row.joint, row.kind) for row in structure.redundant] == (
        [("second", "cd")] * 3 + [("second", "dp1")] * 2)
    assert all("revolute 'second'" in row.label for row in structure.redundant)


def test_independent_rows_flags_a_repeated_row(rng):
    matrix = rng.normal(size=(3, 6))
    stacked = np.vstack([matrix, matrix[1] * 2.0 - matrix[0], rng.normal(size=6)])
    assert checks.independent_rows(stacked) == [True, True, True, False, True]
