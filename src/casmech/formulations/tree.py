"""The spanning tree of the joint formulation: which joints carry joint coordinates.

Rule: breadth first from ground, visiting each body's joints in file order; the first joint
that reaches a body is its tree joint (the body is its child), if its type has a tree motion
(casmech.elements.joint_types.MOTIONS) and the file does not say `cut: true`. Every other joint is
cut: it
stays a set of constraint rows (a loop closure). A body no tree joint reaches from ground
floats: a `free` tree joint from ground (then the breadth-first search continues from it, in
file order of the bodies).

The joint frames are numbers (NumPy) for a numeric IR, SX of the model data for a parametric
one (model.parametric.split); the tree itself depends on the structure alone.
"""

from __future__ import annotations

from collections import deque
from dataclasses import field

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.elements.joint_types import MOTIONS
from casmech.model.ir import GROUND_INDEX, JointIR, ModelIR
from casmech.schema.resolved import ScalarFunction

Frame = tuple  # (axes as columns, origin), in a body's frame: NumPy arrays or SX
# an entry of a numeric joint frame's axis or point of at most RESIDUE times that vector's
# largest entry is the rounding residue of the arithmetic that placed the frame on its body
# (an axis off by less than 1e-15 rad, a point by 1e-15 of its distance): an exact zero in
# the tree, so that the build folds its products away (docs/decisions/joint-ode-code-size.md)
RESIDUE = 4 * np.finfo(float).eps


@record
class TreeJoint:
    """A tree joint: its motion type, parent and child bodies and joint frames on each."""

    name: str  # the file's joint ("" for a floating body's free joint)
    type: str  # key of MOTIONS
    parent: int  # body index (GROUND_INDEX: ground)
    child: int
    parent_frame: Frame
    child_frame: Frame
    reversed: bool = False  # the file's body_i is the child
    # coordinate index -> (f(t), sign): coordinates a driver prescribes (sign -1 if reversed)
    prescribed: dict[int, tuple[ScalarFunction, float]] = field(default_factory=dict)
    joint: JointIR | None = None


@record
class Tree:
    joints: tuple[TreeJoint, ...]  # every body once as a child, parents before children
    cut: tuple[JointIR, ...]  # joints kept as constraint rows

    @property
    def is_tree(self) -> bool:
        return not self.cut

    @property
    def floating_loops(self) -> bool:
        """Loops through a floating body (a `free` tree joint, its body held by cut rows only):
        its joint coordinates are its r-p ones plus the recursion's overhead (auto runs rp)."""
        return not self.is_tree and any(joint.joint is None for joint in self.joints)

    @property
    def couplings(self) -> tuple[JointIR, ...]:
        """Couplings of joint coordinates (gear, rack_pinion, coupler): always cut, their rows
        closure rows over the bodies of several joints (joint_system.rows_of); a formulation
        whose takes_couplings is False refuses them (runtime.auto_formulation)."""
        return tuple(joint for joint in self.cut if joint.couples)


def spanning_tree(ir: ModelIR) -> Tree:
    """The tree of the module docstring."""
    reached = {GROUND_INDEX}
    tree: list[TreeJoint] = []
    used: set[str] = set()
    at: dict[int, list[JointIR]] = {}  # body -> its joints, in file order
    for joint in ir.joints:
        for k in dict.fromkeys((joint.body_i, joint.body_j)):
            at.setdefault(k, []).append(joint)

    def search(start: int) -> None:
        queue = deque([start])
        while queue:
            body = queue.popleft()
            for joint in at.get(body, ()):
                other = _other(joint, body)
                if other is None or other in reached or not _can_be_tree(joint):
                    continue
                tree.append(tree_joint(joint, parent=body))
                used.add(joint.name)
                reached.add(other)
                queue.append(other)

    search(GROUND_INDEX)
    for k in range(ir.n_bodies):
        if k not in reached:
            tree.append(free_joint(k))
            reached.add(k)
            search(k)
    cut = tuple(j for j in ir.joints if j.name not in used)
    return Tree(tuple(tree), cut)


def _other(joint: JointIR, body: int) -> int | None:
    if joint.body_i == body:
        return joint.body_j
    return joint.body_i if joint.body_j == body else None


def _can_be_tree(joint: JointIR) -> bool:
    return joint.type in MOTIONS and not joint.cut and joint.body_i != joint.body_j


def free_joint(body: int) -> TreeJoint:
    identity = (np.eye(3), np.zeros(3))
    return TreeJoint("", "free", GROUND_INDEX, body, identity, identity)


def tree_joint(joint: JointIR, parent: int) -> TreeJoint:
    reversed_ = joint.body_i != parent
    sides = ("j", "i") if reversed_ else ("i", "j")
    child = joint.body_i if reversed_ else joint.body_j
    motion = MOTIONS[joint.type]
    frames = tuple(_without_residues(frame)
                   for frame in FRAMES[motion.frame](joint.geometry, *sides))
    sign = -1.0 if reversed_ else 1.0
    prescribed = {motion.drivers[key]: (f, sign) for key, f in joint.drivers.items()}
    return TreeJoint(joint.name, joint.type, parent, child, *frames, reversed_, prescribed,
                     joint)


def _without_residues(frame: Frame) -> Frame:
    """A numeric frame with its residues (RESIDUE) made zeros; SX as it is."""
    axes, origin = frame
    if isinstance(axes, ca.SX) or isinstance(origin, ca.SX):
        return frame
    axes, origin = np.array(axes, float), np.array(origin, float)
    axes[np.abs(axes) <= RESIDUE * np.abs(axes).max(axis=0)] = 0.0
    origin[np.abs(origin) <= RESIDUE * np.abs(origin).max(initial=0.0)] = 0.0
    return axes, origin


def _axes_frames(geometry, parent: str, child: str) -> tuple[Frame, Frame]:
    """The joint's triad u, v, w and point P on both bodies."""
    def frame(side: str) -> Frame:
        columns = [geometry[f"{k}@{side}"] for k in "uvw"]
        symbolic = any(isinstance(c, ca.SX) for c in columns)
        return (ca.horzcat(*columns) if symbolic else np.column_stack(columns),
                geometry[f"P@{side}"])
    return frame(parent), frame(child)


def _cross_frames(geometry, parent: str, child: str) -> tuple[Frame, Frame]:
    """Universal joint: the parent's axis is F_p's x, the child's axis F_c's y (each made
    perpendicular to the other one's direction at the file's pose)."""
    axis = {"i": "axis_i", "j": "axis_j"}
    a_p, a_c = axis[parent], axis[child]

    def triad(x, y, exact: str):
        ops = SX_OPS if isinstance(x, ca.SX) or isinstance(y, ca.SX) else NUMPY_OPS
        norm, dot, cross, columns = ops
        x, y = x / norm(x), y / norm(y)
        if exact == "x":
            y = y - dot(y, x) * x
        else:
            x = x - dot(x, y) * y
        x, y = x / norm(x), y / norm(y)
        return columns([x, y, cross(x, y)])

    parent_axes = triad(geometry[f"{a_p}@{parent}"], geometry[f"{a_c}@{parent}"], "x")
    child_axes = triad(geometry[f"{a_p}@{child}"], geometry[f"{a_c}@{child}"], "y")
    return (parent_axes, geometry[f"P@{parent}"]), (child_axes, geometry[f"P@{child}"])


# (norm, dot, cross, columns) on numbers and on SX
NUMPY_OPS = (np.linalg.norm, lambda a, b: a @ b, np.cross, np.column_stack)
SX_OPS = (ca.norm_2, ca.dot, ca.cross, lambda vs: ca.horzcat(*vs))

FRAMES = {"axes": _axes_frames, "cross": _cross_frames}
