"""The start of the joint formulation from body coordinates: each tree joint's coordinates and
velocities from the r-p state (relative pose -> theta, relative twist -> u through the joint's
motion subspace), the loop closures' rows masked out at t0 and their consistent multipliers,
and the quaternion signs that make the tree's Euler parameters continue the r-p state's."""

from __future__ import annotations

from functools import cache

import numpy as np

from casmech.core.options import Assembly
from casmech.elements.joint_types import MOTIONS
from casmech.equations.checks import independent_rows
from casmech.formulations.articulated import local_motion
from casmech.formulations.joint_system import JointSystem, layout
from casmech.formulations.tree import Tree, TreeJoint

ASSEMBLY = Assembly()  # the defaults (core.options)


@cache
def constant_inverse(kind: str) -> np.ndarray | None:
    """The pseudo-inverse of a joint type's motion subspace S_J where S_J is the same at every
    theta (revolute, spherical, ...: u = S_J^+ twist with no per-state work), else None.
    Whether it is constant is seen at sample coordinates (its SX does not simplify
    sin^2 + cos^2: a revolute's S_J is a constant written with theta in it)."""
    motion = MOTIONS[kind]
    # four scattered coordinates (not numpy.random, which a run would have to import)
    samples = np.sin(1.7 * np.arange(1, 4 * motion.n_q + 1)).reshape(4, motion.n_q) * 1.5
    for start in motion.quaternions:
        samples[:, start:start + 4] /= np.linalg.norm(samples[:, start:start + 4], axis=1)[:, None]
    zero = np.zeros(motion.n_v)
    subspaces = [np.array(local_motion(kind)(theta, zero)[2].full()) for theta in samples]
    if max(np.max(np.abs(s - subspaces[0])) for s in subspaces) > 1e-14:
        return None
    return np.linalg.pinv(subspaces[0])



def joint_state(joint: TreeJoint, rotation, gap, twist) -> tuple[np.ndarray, np.ndarray]:
    """(theta, u) of a tree joint from its relative rotation, gap and twist (relative_states)."""
    theta = MOTIONS[joint.type].coordinates(rotation, gap)
    n_v = MOTIONS[joint.type].n_v
    if not n_v:
        return theta, np.zeros(0)
    inverse = constant_inverse(joint.type)
    if inverse is not None:
        return theta, inverse @ twist
    subspace = np.array(local_motion(joint.type)(theta, np.zeros(n_v))[2].full())
    return theta, np.linalg.lstsq(subspace, twist, rcond=None)[0]


def initial_state(system: JointSystem, q, q_dot) -> np.ndarray:
    """x0 = [theta; u] of the free coordinates and velocities at the r-p state."""
    relative = (np.array(v.full()) for v in system.relative_states(q, q_dot))
    return from_relative(system.tree, *relative)


def from_relative(tree: Tree, rotations, gaps, twists) -> np.ndarray:
    """x0 = [theta; u] of the free coordinates and velocities from every tree joint's relative
    states (JointSystem.relative_states: rotations 3 x 3n, gaps 3 x n, twists 6 x n)."""
    lay = layout(tree)
    x0 = np.zeros(lay.n_x)
    for k, joint in enumerate(tree.joints):
        theta, u = joint_state(joint, rotations[:, 3 * k:3 * k + 3], gaps[:, k], twists[:, k])
        x0[list(lay.theta[k])] = theta[list(lay.free_theta[k])]
        x0[list(lay.u[k])] = u[list(lay.free_u[k])]
    return x0


class Loops:
    """Consistent multipliers of the loop closures and the rows masked out at t0."""

    def __init__(self, system: JointSystem, t0: float, x0, settings: Assembly = ASSEMBLY):
        self.system, m = system, system.n_cut
        self.n_z = 2 * m
        jacobian = np.array(system.velocity_jacobian(t0, x0).full()) if m else np.zeros((0, 0))
        keep = independent_rows(jacobian, settings.linear_algebra) if m else []
        self.mask = 1.0 - np.array(keep, float)

    def z(self, t: float, x) -> np.ndarray:
        """[lam; mu = 0] with lam making the constraint accelerations vanish."""
        m = self.system.n_cut
        if not m:
            return np.zeros(0)
        matrix, base = (np.array(v.full()) for v in self.system.acceleration_system(t, x))
        keep = np.flatnonzero(self.mask == 0)
        z = np.zeros(2 * m)
        if len(keep):
            z[keep] = np.linalg.lstsq(matrix[np.ix_(keep, keep)], -base[keep, 0],
                                      rcond=None)[0]
        return z


def quaternion_signs(system: JointSystem, t0: float, x0, z0, q0, n_bodies: int):
    """+1 or -1 per body, so the tree's Euler parameters continue the r-p state's."""
    q = np.array(system.motion(t0, x0, z0, np.ones(n_bodies))[0].full()).ravel()
    return continuing_signs(q, q0, n_bodies)


def continuing_signs(q_tree, q0, n_bodies: int) -> np.ndarray:
    """+1 or -1 per body: the sign that turns the Euler parameters of the r-p positions q_tree
    into those continuing q0's (a negative dot product flips them)."""
    p_tree = np.ravel(q_tree)[3 * n_bodies:].reshape(n_bodies, 4)
    p_rp = np.ravel(q0)[3 * n_bodies:].reshape(n_bodies, 4)
    return np.where(np.sum(p_tree * p_rp, axis=1) < 0, -1.0, 1.0)
