"""A URDF robot as a tree of links and joints; its pose and velocities at given joint values.

Conventions (URDF): a joint's `origin` is the child link's frame in the parent link's frame at
joint value 0; `rpy` are fixed-axis roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll)); the joint
`axis` is in the joint (= child link) frame; an `inertial` gives the centre of mass and the
inertia tensor's frame in the link frame, its `ixy`... being the tensor's entries.
"""

from __future__ import annotations

from dataclasses import field

import numpy as np

from casmech.core.records import record
from casmech.importers.urdf_read import Element, Reader

MOVING = {"revolute": "revolute", "continuous": "revolute", "prismatic": "translational",
          "planar": "planar"}  # URDF joint type -> casmech joint type
TYPES = (*MOVING, "fixed", "floating")
ROTATING = ("revolute", "continuous")


def rpy_matrix(rpy) -> np.ndarray:
    (cr, cp, cy), (sr, sp, sy) = np.cos(rpy), np.sin(rpy)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def axis_rotation(axis, angle: float) -> np.ndarray:
    x, y, z = axis
    skew = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + np.sin(angle) * skew + (1 - np.cos(angle)) * skew @ skew


@record(eq=False)
class Frame:
    """A frame: rotation (columns = its axes) and origin, in the frame it is given in."""

    rotation: np.ndarray
    origin: np.ndarray

    def __mul__(self, other: Frame) -> Frame:
        return Frame(self.rotation @ other.rotation,
                     self.origin + self.rotation @ other.origin)

    def point(self, local) -> np.ndarray:
        return self.origin + self.rotation @ np.asarray(local, float)


IDENTITY = Frame(np.eye(3), np.zeros(3))


@record(frozen=False, eq=False)
class Inertial:
    mass: float
    frame: Frame  # of the centre of mass and the tensor's axes, in the link frame
    tensor: np.ndarray  # about the centre of mass, in `frame`'s axes


@record(frozen=False, eq=False)
class Link:
    name: str
    element: Element
    inertial: Inertial | None
    visuals: list[Element] = field(default_factory=list)


@record(frozen=False, eq=False)
class Joint:
    name: str
    element: Element
    type: str
    parent: str
    child: str
    origin: Frame
    axis: np.ndarray  # unit vector in the joint frame

    def motion(self, value: float) -> Frame:
        if self.type in ROTATING:
            return Frame(axis_rotation(self.axis, value), np.zeros(3))
        if self.type == "prismatic":
            return Frame(np.eye(3), self.axis * value)
        return IDENTITY


def frame(reader: Reader, element: Element | None, path: str) -> Frame:
    """The frame of an <origin> element (identity when absent)."""
    if element is None:
        return IDENTITY
    rpy = reader.numbers(element, path, "rpy", 3, (0.0, 0.0, 0.0))
    return Frame(rpy_matrix(rpy), reader.numbers(element, path, "xyz", 3, (0.0, 0.0, 0.0)))


def inertial(reader: Reader, element: Element | None, path: str) -> Inertial | None:
    if element is None:
        return None
    mass_element = element.find("mass")
    if mass_element is None:
        raise reader.error(element, path, "<inertial> has no <mass>", '<mass value="..."/>',
                           code="E100")
    mass = reader.number(mass_element, f"{path}.mass", "value")
    if mass < 0:
        raise reader.error(mass_element, f"{path}.mass", "the mass is negative",
                           "a mass >= 0 [kg]", code="E400", got=str(mass))
    tensor_element = element.find("inertia")
    names = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    if tensor_element is None:
        raise reader.error(element, path, "<inertial> has no <inertia>",
                           "<inertia " + " ".join(f'{n}="..."' for n in names) + "/>",
                           code="E100")
    xx, xy, xz, yy, yz, zz = (reader.number(tensor_element, f"{path}.inertia", n, 0.0)
                              for n in names)
    tensor = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    return Inertial(mass, frame(reader, element.find("origin"), f"{path}.origin"), tensor)


def read_link(reader: Reader, element: Element) -> Link:
    name = reader.text(element, "link", "name")
    path = f"link[{name}]"
    return Link(name, element, inertial(reader, element.find("inertial"), f"{path}.inertial"),
                element.findall("visual"))


def read_joint(reader: Reader, element: Element) -> Joint:
    name = reader.text(element, "joint", "name")
    path = f"joint[{name}]"
    kind = reader.text(element, path, "type")
    if kind not in TYPES:
        raise reader.error(element, f"{path}.type", f"unsupported joint type '{kind}'",
                           "one of " + ", ".join(TYPES), code="E103", got=kind,
                           hint="casmech translates the URDF joint types")
    ends = {}
    for end in ("parent", "child"):
        end_element = element.find(end)
        if end_element is None:
            raise reader.error(element, path, f"joint '{name}' has no <{end}>",
                               f'<{end} link="..."/>', code="E100")
        ends[end] = reader.text(end_element, f"{path}.{end}", "link")
    axis = reader.numbers(element.find("axis"), f"{path}.axis", "xyz", 3, (1.0, 0.0, 0.0))
    if kind in MOVING and np.linalg.norm(axis) < 1e-12:
        raise reader.error(element.find("axis"), f"{path}.axis", "the joint axis is zero",
                           "a non-zero direction", code="E404")
    axis = axis / (np.linalg.norm(axis) or 1.0)
    return Joint(name, element, kind, ends["parent"], ends["child"],
                 frame(reader, element.find("origin"), f"{path}.origin"), axis)


@record(frozen=False)
class Tree:
    links: dict[str, Link]
    joints: list[Joint]  # parents before children (depth first, in file order)
    root: str

    def joint_of(self, link: str) -> Joint | None:
        return next((j for j in self.joints if j.child == link), None)


def _unique(reader: Reader, items, kind: str) -> dict:
    named: dict = {}
    for item in items:
        if item.name in named:
            raise reader.error(item.element, f"{kind}[{item.name}]", f"a second {kind} named "
                               f"'{item.name}'", f"a {kind} name used once", code="E301",
                               hint=f"the first is at line {named[item.name].element.line}")
        named[item.name] = item
    return named


def _bounded(reader: Reader) -> None:
    """E105 beyond casmech's bound on a model's items (schema.repeat.MAX_ITEMS)."""
    from casmech.schema import repeat

    items = [e for e in reader.root.children if e.tag in ("link", "joint")]
    if len(items) > repeat.MAX_ITEMS:
        raise reader.error(items[repeat.MAX_ITEMS], "robot", f"the robot has more than "
                           f"{repeat.MAX_ITEMS} links and joints", "a robot casmech can "
                           "build", code="E105", hint=repeat.TOO_MANY_HINT)


def read_tree(reader: Reader) -> Tree:
    """The links and joints of the robot, checked to form one tree."""
    _bounded(reader)
    links = _unique(reader, [read_link(reader, e) for e in reader.root.findall("link")], "link")
    joints = list(_unique(reader, [read_joint(reader, e) for e in reader.root.findall("joint")],
                          "joint").values())
    if not links:
        raise reader.error(reader.root, "robot", "the robot has no <link>",
                           "<link name=\"...\"> elements", code="E100")
    parent_of: dict[str, Joint] = {}
    for joint in joints:
        for end in ("parent", "child"):
            name = getattr(joint, end)
            if name not in links:
                raise reader.error(joint.element.find(end), f"joint[{joint.name}].{end}",
                                   f"unknown link '{name}'", "the name of a <link>",
                                   code="E300", got=name, hint=_known(name, links))
        if joint.child in parent_of:
            raise reader.error(joint.element, f"joint[{joint.name}]", f"link '{joint.child}' "
                               f"has a second parent joint (the first: "
                               f"'{parent_of[joint.child].name}')", "a tree: one parent joint "
                               "per link", code="E103",
                               hint="URDF describes trees; close a loop in the casmech YAML")
        parent_of[joint.child] = joint
    roots = [name for name in links if name not in parent_of]
    if len(roots) != 1:
        where = links[roots[1]].element if len(roots) > 1 else reader.root
        raise reader.error(where, "robot", "the links do not form one tree: "
                           + (f"{len(roots)} links have no parent ({', '.join(roots)})"
                              if roots else "every link has a parent (a loop)"),
                           "one root link; every other link the child of one joint",
                           code="E103")
    order = _depth_first(roots[0], joints)
    if len(order) != len(joints):
        reached = {j.name for j in order}
        lost = next(j for j in joints if j.name not in reached)
        raise reader.error(lost.element, f"joint[{lost.name}]", "the joint is part of a loop "
                           "not connected to the root link", "a tree", code="E103")
    return Tree(links, order, roots[0])


def _known(name: str, links: dict) -> str:
    from casmech.errors import did_you_mean

    return did_you_mean(name, links) or f"links: {', '.join(list(links)[:10])}"


def _depth_first(root: str, joints: list[Joint]) -> list[Joint]:
    children: dict[str, list[Joint]] = {}
    for joint in joints:
        children.setdefault(joint.parent, []).append(joint)
    order, stack = [], list(reversed(children.get(root, [])))
    while stack:
        joint = stack.pop()
        order.append(joint)
        stack.extend(reversed(children.get(joint.child, [])))
    return order


@record(frozen=False)
class State:
    """Every link's frame (global), angular velocity and the velocity of its frame's origin."""

    frames: dict[str, Frame]
    omega: dict[str, np.ndarray]
    velocity: dict[str, np.ndarray]


def pose(tree: Tree, positions: dict[str, float], velocities: dict[str, float]) -> State:
    """Forward kinematics from the root link (at the global frame, at rest)."""
    state = State({tree.root: IDENTITY}, {tree.root: np.zeros(3)}, {tree.root: np.zeros(3)})
    for joint in tree.joints:
        parent = state.frames[joint.parent]
        joint_frame = parent * joint.origin
        child = joint_frame * joint.motion(positions.get(joint.name, 0.0))
        rate = velocities.get(joint.name, 0.0) * (joint_frame.rotation @ joint.axis)
        omega = state.omega[joint.parent]
        state.frames[joint.child] = child
        state.omega[joint.child] = omega + (rate if joint.type in ROTATING else 0.0)
        state.velocity[joint.child] = state.velocity[joint.parent] + np.cross(
            omega, child.origin - parent.origin) + (rate if joint.type == "prismatic" else 0.0)
    return state
