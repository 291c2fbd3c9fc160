"""URDF robot description (.urdf) -> casmech model (an `Imported`, written by emit.to_yaml).

Translated:
- the root link is the ground; a link joined by a `fixed` joint is merged into its parent's body
  (masses, centres of mass and inertias combined; its visuals kept), as MuJoCo's URDF import
  does (fusestatic);
- every other link is a body: its frame's axes are the body's axes, its origin the combined
  centre of mass; mass and inertia from `inertial` (rotated from the inertial frame into the link
  frame); `visual` box, cylinder, sphere and mesh become `geometry`;
- joints: revolute and continuous -> revolute, prismatic -> translational, planar -> planar
  (axis = the plane's normal), floating -> none (a free body); placed at the initial pose;
- `dynamics damping` -> an rsda (revolute) or a tsda along the axis (prismatic) with that damping;
- `limit` is written as a comment on the joint (casmech has no joint limits).
Not translated (a warning naming the line): `mimic`, `friction`, `calibration`,
`safety_controller`, `transmission`, `gazebo` and other extensions; `collision` elements are
skipped (casmech has no contact). URDF has no gravity: the model gets [0, 0, -9.81].

The initial pose is the one at the joint values `positions` (default 0, the URDF's reference
pose) with joint rates `velocities` (default 0); casmech's joint angles are measured from it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from casmech.core.quaternions import from_matrix
from casmech.errors import UsageError, did_you_mean
from casmech.importers.adm_frames import tidy
from casmech.importers.emit import Imported, Item, identifier
from casmech.importers.urdf_geometry import geometry_items
from casmech.importers.urdf_read import Reader
from casmech.importers.urdf_tree import MOVING, Frame, Joint, Link, State, Tree, pose, read_tree

GRAVITY = [0.0, 0.0, -9.81]
DAMPER_LENGTH = 1.0  # [m] distance between the two points of a prismatic joint's damper
SKIPPED = {"collision"}  # link children skipped without a warning (said in the header)
KNOWN = {"robot": {"link", "joint", "material"}, "link": {"inertial", "visual", "collision"},
         "joint": {"parent", "child", "origin", "axis", "limit", "dynamics"}}
HINTS = {"mimic": "a mimic joint can be written by hand as a basic constraint (docs/import.md)",
         "transmission": "actuation: add motors or forces by hand (docs/motors.md)"}


@dataclass
class Group:
    """Links welded together by fixed joints: one casmech body (or the ground)."""

    head: str  # the link whose frame is the body's
    members: list[tuple[Link, Frame]] = field(default_factory=list)  # frames in head's frame
    fused: list[Joint] = field(default_factory=list)

    def mass_properties(self) -> tuple[float, np.ndarray, np.ndarray]:
        """Mass, centre of mass and inertia about it, in the head link's frame."""
        parts = [(m.inertial.mass, at * m.inertial.frame, m.inertial.tensor)
                 for m, at in self.members if m.inertial is not None and m.inertial.mass > 0]
        mass = sum(p[0] for p in parts)
        if mass <= 0:
            return 0.0, np.zeros(3), np.zeros((3, 3))
        centre = sum(m * f.origin for m, f, _ in parts) / mass
        inertia = np.zeros((3, 3))
        for m, f, tensor in parts:
            d = f.origin - centre
            inertia += f.rotation @ tensor @ f.rotation.T + m * (d @ d * np.eye(3) - np.outer(d, d))
        return mass, centre, inertia


def groups(tree: Tree) -> dict[str, Group]:
    """Link name -> its group (the root's group is the ground's)."""
    of = {tree.root: Group(tree.root, [(tree.links[tree.root], Frame(np.eye(3), np.zeros(3)))])}
    at = {tree.root: of[tree.root].members[0][1]}
    for joint in tree.joints:
        link = tree.links[joint.child]
        if joint.type == "fixed":
            group = of[joint.parent]
            at[joint.child] = at[joint.parent] * joint.origin
            group.fused.append(joint)
        else:
            group = Group(joint.child)
            at[joint.child] = Frame(np.eye(3), np.zeros(3))
        group.members.append((link, at[joint.child]))
        of[joint.child] = group
    return of


class Names:
    """casmech names (identifiers, unique among bodies, joints and forces; `ground` reserved)."""

    def __init__(self):
        self.used = {"ground"}

    def __call__(self, text: str, suffix: str) -> str:
        name = identifier(text, suffix.strip("_"))
        if name in self.used:
            name = f"{name}{suffix}"
        base, k = name, 2
        while name in self.used:
            name, k = f"{base}_{k}", k + 1
        self.used.add(name)
        return name


class Translator:
    def __init__(self, reader: Reader, tree: Tree, state: State):
        self.reader, self.tree, self.state = reader, tree, state
        self.model = Imported(name=reader.root.attrib.get("name", "robot"), description="",
                              header=[])
        self.groups = groups(tree)
        self.names = Names()
        self.body_names = {tree.root: "ground"}  # head link -> casmech body

    def warn_unknown(self, element, path: str, kind: str) -> None:
        for child in element.children:
            if child.tag not in KNOWN[kind] and child.tag not in SKIPPED:
                self.reader.warn(child, path, f"<{child.tag}> not translated",
                                 hint=HINTS.get(child.tag))

    def body(self, group: Group) -> None:
        reader, link = self.reader, self.tree.links[group.head]
        path = f"link[{link.name}]"
        mass, centre, inertia = group.mass_properties()
        if mass <= 0:
            joint = self.tree.joint_of(link.name)
            raise reader.error(link.element, path, f"link '{link.name}' moves (joint "
                               f"'{joint.name}' is {joint.type}) but has no mass",
                               "an <inertial> with a <mass value> > 0", code="E400"
                               if link.inertial else "E100",
                               hint="casmech bodies need mass and inertia; merge a massless "
                               "link into a neighbour, or give it a small inertial")
        frame = self.state.frames[link.name]
        omega = self.state.omega[link.name]
        position = frame.point(centre)
        velocity = self.state.velocity[link.name] + np.cross(omega, position - frame.origin)
        name = self.names(link.name, "_link")
        self.body_names[link.name] = name
        data = {"name": name, "mass": mass, "inertia": self.inertia(inertia),
                "position": tidy(position)}
        if not np.allclose(frame.rotation, np.eye(3), rtol=0, atol=1e-15):
            data["orientation"] = {"euler_parameters": tidy(from_matrix(frame.rotation))}
        if np.any(velocity):
            data["velocity"] = tidy(velocity)
        if np.any(omega):
            data["angular_velocity"] = tidy(omega)
        shapes = geometry_items(reader, group.members, centre)
        if shapes:
            data["geometry"] = shapes
        comments = [f"link {link.name} (line {link.element.line}); body axes = the link frame's"]
        comments += [f"link {j.child} (line {self.tree.links[j.child].element.line}) merged in "
                     f"by the fixed joint {j.name} (line {j.element.line})" for j in group.fused]
        for member, _ in group.members:
            self.warn_unknown(member.element, f"link[{member.name}]", "link")
        self.model.bodies.append(Item(data, comments))

    @staticmethod
    def inertia(tensor: np.ndarray) -> list[float]:
        scale = np.max(np.abs(tensor))
        (xx, xy, xz), (_, yy, yz), (_, _, zz) = tensor
        values = tidy([xx, yy, zz, xy, xz, yz], scale)
        return values[:3] if not any(values[3:]) else values

    def joint(self, joint: Joint) -> None:
        path = f"joint[{joint.name}]"
        self.warn_unknown(joint.element, path, "joint")
        if joint.type == "fixed":
            return
        body_i = self.body_names[self.groups[joint.parent].head]
        body_j = self.body_names[joint.child]
        if joint.type == "floating":
            self.model.trailer.append(f"joint {joint.name} (line {joint.element.line}) is "
                                      f"floating: {body_j} is a free body")
            return
        name = self.names(joint.name, "_joint")
        frame = self.state.frames[joint.child]
        axis = frame.rotation @ joint.axis
        data = {"name": name, "type": MOVING[joint.type], "body_i": body_i, "body_j": body_j,
                "at": tidy(frame.origin), "axis": tidy(axis)}
        comments = [f"{joint.type} joint {joint.name} (line {joint.element.line})"]
        comments += self.limit(joint, path)
        self.model.joints.append(Item(data, comments))
        self.damper(joint, path, data)

    def limit(self, joint: Joint, path: str) -> list[str]:
        element = joint.element.find("limit")
        if element is None or joint.type not in ("revolute", "prismatic", "continuous"):
            return []
        units = dict(zip(("lower", "upper", "effort", "velocity"), (
            ("m", "m", "N", "m/s") if joint.type == "prismatic" else
            ("rad", "rad", "N m", "rad/s")), strict=True))
        text = ", ".join(f"{key} {self.reader.number(element, f'{path}.limit', key):g} {unit}"
                         for key, unit in units.items() if key in element.attrib)
        return [f"URDF limit (line {element.line}): {text}; not enforced: casmech has no "
                "joint limits"]

    def damper(self, joint: Joint, path: str, data: dict) -> None:
        element = joint.element.find("dynamics")
        damping = self.reader.number(element, f"{path}.dynamics", "damping", 0.0) \
            if element is not None else 0.0
        if element is not None and "friction" in element.attrib:
            self.reader.warn(element, f"{path}.dynamics", "friction not translated",
                             hint="casmech has no joint friction; add a force by hand")
        if not damping:
            return
        name = self.names(f"{data['name']}_damping", "_force")
        comment = [f"dynamics damping of joint {joint.name} (line {element.line})"]
        if joint.type in ("revolute", "continuous"):
            force = {"name": name, "type": "rsda", "joint": data["name"], "damping": damping}
        elif joint.type == "prismatic":  # two points on the axis: the damper's line is the axis
            far = np.asarray(data["at"]) + DAMPER_LENGTH * np.asarray(data["axis"])
            force = {"name": name, "type": "tsda", "body_i": data["body_i"], "at_i": data["at"],
                     "body_j": data["body_j"], "at_j": tidy(far), "damping": damping}
            comment.append(f"a damper along the axis, its points {DAMPER_LENGTH:g} m apart")
        else:
            self.reader.warn(element, f"{path}.dynamics", f"damping of a {joint.type} joint "
                             "not translated")
            return
        self.model.forces.append(Item(force, comment))


def _check_values(tree: Tree, values: dict[str, float], what: str) -> None:
    movable = [j.name for j in tree.joints if j.type in ("revolute", "continuous", "prismatic")]
    for name, value in values.items():
        if name not in movable:
            raise UsageError(f"initial joint {what}: '{name}' is not a revolute, continuous or "
                             f"prismatic joint of the robot"
                             + (f"; {did_you_mean(name, movable)}" if did_you_mean(name, movable)
                                else f"; joints: {', '.join(movable)}"))
        if not np.isfinite(value):
            raise UsageError(f"initial joint {what} of '{name}' is not a finite number")


def import_urdf(path: Path, positions: dict[str, float] | None = None,
                velocities: dict[str, float] | None = None) -> Imported:
    """The casmech model of a URDF file, posed at the joint `positions` [rad or m] with joint
    `velocities` [rad/s or m/s] (by URDF joint name; default 0)."""
    reader = Reader.read(Path(path))
    tree = read_tree(reader)
    positions, velocities = dict(positions or {}), dict(velocities or {})
    _check_values(tree, positions, "position")
    _check_values(tree, velocities, "velocity")
    translator = Translator(reader, tree, pose(tree, positions, velocities))
    heads = [tree.root] + [j.child for j in tree.joints if j.type != "fixed"]
    for head in heads[1:]:
        translator.body(translator.groups[head])
    for joint in tree.joints:
        translator.joint(joint)
    translator.warn_unknown(reader.root, "robot", "robot")
    return _finish(translator, Path(path), positions, velocities)


def _finish(translator: Translator, path: Path, positions: dict, velocities: dict) -> Imported:
    model, tree = translator.model, translator.tree
    ground = translator.groups[tree.root]
    mass = ground.mass_properties()[0]
    model.description = f"URDF robot {model.name} ({path.name})"
    model.header = [f"Imported by `casmech import` from the URDF file {path.name}.",
                    f"Root link {tree.root} is the ground" + (
                        f" (with the links fixed to it: {mass:g} kg, not part of the model)"
                        if mass > 0 else "") + "; links joined by fixed joints are merged.",
                    "Body frames: each link's axes at the link's centre of mass. collision "
                    "elements are not translated.",
                    "Initial joint values (URDF joint: position, velocity): " + (", ".join(
                        f"{name}: {positions.get(name, 0.0):g}, {velocities.get(name, 0.0):g}"
                        for name in sorted({*positions, *velocities})) or "all 0") + ".", ""]
    model.gravity = GRAVITY
    model.gravity_comments = ["URDF has no gravity: the ROS convention, z up"]
    model.warnings = translator.reader.warnings
    return model
