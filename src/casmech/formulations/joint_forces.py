"""The joint formulation's applied forces: body wrenches, and generalized forces on the tree
joints' coordinates of the elements local to one tree joint.

An element is local to a tree joint when it acts between that joint's two bodies, its law
reads t and the motion of one body relative to the other only (equations.force_laws.relative:
a tsda, an rsda, a joint's stop or effort motor), no driver prescribes a coordinate of the
joint and the joint's coordinates hold no quaternion (a spherical or free joint's elements
stay body wrenches). Its law is then a function of that joint's coordinates theta and
velocities u alone: `JointCoordinates` places the two bodies by the joint's motion relative
to its parent frame F_p (the law is invariant under a common rigid motion of the pair), so
the same law (equations.force_laws.FORCE_ELEMENTS) gives its generalized force over theta,
and virtual power the one along u, tau = (d theta_dot / d u)^T Q_theta: its derivative stays
on the joint's own coordinates instead of running through the kinematic chain. A cut joint
has no coordinates, so its elements stay body wrenches, as do gravity, one-body loads,
elements between bodies of different tree joints and laws that read other state
(articulated.applied_wrenches).

The constraint wrench of a tree joint (the results row's multipliers) is the Newton-Euler
balance of its subtree with every applied force a body wrench: `local_wrenches` gives the
local elements' body wrenches for it (articulated.joint_wrenches' `applied`), so the
reactions are those of the body-wrench evaluation whatever direction an element acts in.
"""

from __future__ import annotations

from dataclasses import replace
from functools import cached_property

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.elements.joint_types import MOTIONS
from casmech.elements.primitives import Frame
from casmech.equations.force_kernels import on_ground
from casmech.equations.force_laws import FORCE_ELEMENTS, relative
from casmech.formulations import articulated, rnea
from casmech.formulations.articulated import Joint, Kinematics
from casmech.formulations.tree import Tree, TreeJoint
from casmech.model.ir import ForceIR, ModelIR

GROUPS = ("forces", "motors", "limits")  # the ModelIR fields that hold elements with a law


@record
class Applied:
    """A model's applied forces split for a tree: `bodies` the IR whose forces act as body
    wrenches, `local` per tree joint (tree order) its local elements, `only_local` the IR of
    the local elements alone (no gravity): their body wrenches, for the multipliers."""

    bodies: ModelIR
    local: tuple[tuple[ForceIR, ...], ...]
    only_local: ModelIR

    @property
    def any_local(self) -> bool:
        return any(self.local)


def split(ir: ModelIR, tree: Tree, joint_local: bool = True) -> Applied:
    """The Applied of a tree (module docstring); not `joint_local`: every element a body
    wrench (the body-wrench evaluation, which tests compare against)."""
    pairs = {}
    for index, joint in enumerate(tree.joints):
        if joint.prescribed or MOTIONS[joint.type].quaternions:
            continue
        pairs.setdefault(frozenset((joint.parent, joint.child)), index)
    local: list[list[ForceIR]] = [[] for _ in tree.joints]
    kept: dict[str, list[ForceIR]] = {group: [] for group in GROUPS}
    moved: dict[str, list[ForceIR]] = {group: [] for group in GROUPS}
    for group in GROUPS:
        for element in getattr(ir, group):
            index = pairs.get(frozenset((element.body_i, element.body_j)))
            if (not joint_local or index is None or element.body_i == element.body_j
                    or on_ground(element) or not relative(element)):
                kept[group].append(element)
            else:
                local[index].append(element)
                moved[group].append(element)
    bodies = replace(ir, **{g: tuple(v) for g, v in kept.items()}) if any(moved.values()) \
        else ir
    only_local = replace(ir, gravity=np.zeros(3), **{g: tuple(v) for g, v in moved.items()})
    return Applied(bodies, tuple(tuple(elements) for elements in local), only_local)


class JointCoordinates:
    """What a force law reads of the coordinates (equations.symbols.Coordinates: t, q, q_dot,
    frame(k), point(k, s), rate) over one tree joint: q its coordinates theta, q_dot their
    rates, the frames of its parent and child bodies in its parent frame F_p (the parent body
    fixed, the child placed by the joint's motion)."""

    def __init__(self, joint: TreeJoint, t, theta, u):
        rotation, translation, _, _, theta_dot, matrix = articulated.local_motion(joint.type)(
            theta, u)
        self.t, self.q, self.q_dot = t, theta, theta_dot
        (c_p, s_p), (c_c, s_c) = ((ca.SX(axes), ca.SX(origin)) for axes, origin in
                                  (joint.parent_frame, joint.child_frame))
        a_c = matrix @ c_c.T
        self.frames = {joint.parent: Frame(-c_p.T @ s_p, c_p.T),
                       joint.child: Frame(translation - a_c @ s_c, a_c)}

    def frame(self, k: int) -> Frame:
        return self.frames[k]

    def point(self, k: int, s_bar):
        frame = self.frames[k]
        return frame.r + frame.A @ ca.SX(s_bar)

    def rate(self, expr):
        """The time derivative of an expression of q along q_dot."""
        return ca.jacobian(expr, self.q) @ self.q_dot


def local_torque(joint: TreeJoint, elements: tuple[ForceIR, ...], data=None) -> ca.Function:
    """(theta, u, t (, d)) -> the generalized force of `elements` along the joint's velocities
    u, by their laws over JointCoordinates; `data`: a parametric IR's model data symbols."""
    motion = MOTIONS[joint.type]
    theta, u, t = ca.SX.sym("theta", motion.n_q), ca.SX.sym("u", motion.n_v), ca.SX.sym("t")
    x = JointCoordinates(joint, t, theta, u)
    generalized = sum((ca.SX(FORCE_ELEMENTS[e.type](e, x)[0]) for e in elements),
                      ca.SX.zeros(motion.n_q))
    tau = ca.jacobian(x.q_dot, u).T @ generalized
    extra = [] if data is None else [data]
    return ca.Function(f"local_{joint.name or 'free'}", [theta, u, t, *extra], [tau])


def torques(applied: Applied, joints: list[Joint], t, kin: Kinematics) -> list:
    """Per tree joint, the local elements' generalized force along its free velocities (none:
    zeros)."""
    data = kin.constants.data if kin.constants.symbolic else None
    found = []
    for j, elements in zip(joints, applied.local, strict=True):
        if not elements:
            found.append(ca.SX.zeros(len(j.free), 1))
            continue
        tau = local_torque(j.joint, elements, data)(j.theta, j.u, t,
                                                    *([] if data is None else [data]))
        found.append(tau[j.free])
    return found


def local_wrenches(applied: Applied, t, kin: Kinematics) -> list | None:
    """The local elements' body wrenches at the tree's state (None: there are none)."""
    if not applied.any_local:
        return None
    return articulated.applied_wrenches(applied.only_local, t, kin)


class TreeForces:
    """The applied forces of a tree's state (joints, kin at time t): body wrenches, the
    local elements' joint forces, and the inverse dynamics beyond both."""

    def __init__(self, ir: ModelIR, tree: Tree, joints: list[Joint], kin: Kinematics, t,
                 joint_local: bool = True):
        self.ir, self.joints, self.kin, self.t = ir, joints, kin, t
        self.applied = split(ir, tree, joint_local)

    @cached_property
    def wrenches(self) -> list:
        """The body wrenches of every applied force but the local elements'."""
        return articulated.applied_wrenches(self.applied.bodies, self.t, self.kin)

    @cached_property
    def torques(self) -> list:
        """Per tree joint, its local elements' force along its free velocities."""
        return torques(self.applied, self.joints, self.t, self.kin)

    def inverse_dynamics(self, accelerations: list) -> ca.SX:
        """The joint forces along the free velocities, stacked, beyond the applied forces,
        that give the free accelerations `accelerations` (per tree joint)."""
        tau = rnea.inverse_dynamics(self.ir, self.joints, self.kin, self.wrenches,
                                    accelerations)
        return ca.vertcat(ca.SX(0, 1), *[a - b for a, b in zip(tau, self.torques,
                                                               strict=True)])

    def local_wrenches(self) -> list | None:
        """The local elements' body wrenches (None: there are none)."""
        return local_wrenches(self.applied, self.t, self.kin)
