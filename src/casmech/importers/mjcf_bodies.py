"""The body tree of an MJCF `<worldbody>`: bodies, their joints, geoms, sites and own mass.

Bodies are numbered as MuJoCo numbers them (depth first, in file order), and so are joints,
which gives the layout of a keyframe's qpos and qvel. A `<frame>` places the elements inside
it (and passes on its `childclass`). A joint's `pos` and `axis` are in its body's frame; a
hinge's `ref`, `springref` and `range` are angles in the compiler's unit, turned into radians
here. Cameras and lights are not read (pictures only); anything else not translated is a
warning naming its line.
"""

from __future__ import annotations

from dataclasses import field

import numpy as np

from casmech.core.records import record
from casmech.importers.mjcf_defaults import Compiler, Defaults
from casmech.importers.mjcf_frames import IDENTITY, Frame, frame, fromto
from casmech.importers.mjcf_inertia import Mass, combine, geom_mass, inertial
from casmech.importers.mjcf_read import Element, Reader

JOINT_TYPES = ("hinge", "slide", "ball", "free")
QPOS = {"hinge": 1, "slide": 1, "ball": 4, "free": 7}
QVEL = {"hinge": 1, "slide": 1, "ball": 3, "free": 6}
GEOM_TYPES = ("plane", "hfield", "sphere", "capsule", "ellipsoid", "cylinder", "box", "mesh",
              "sdf")
SIZES = {"sphere": 1, "capsule": 2, "cylinder": 2, "box": 3, "ellipsoid": 3, "plane": 3}
QUIET = {"camera", "light"}  # pictures: skipped without a warning (the header says so)


@record(frozen=False, eq=False)
class Joint:
    name: str
    kind: str
    element: Element
    attrib: dict[str, str]
    pos: np.ndarray  # in the body frame
    axis: np.ndarray  # unit, in the body frame
    ref: float = 0.0  # [rad or m]: the value at the pose written in the file
    springref: float = 0.0
    body: Body | None = None


@record(frozen=False, eq=False)
class Geom:
    name: str
    kind: str
    element: Element
    attrib: dict[str, str]
    size: np.ndarray
    at: Frame  # in the body frame


@record(frozen=False, eq=False)
class Body:
    name: str
    element: Element
    parent: Body | None
    local: Frame  # in the parent body's frame
    childclass: str | None = None
    joints: list[Joint] = field(default_factory=list)
    geoms: list[Geom] = field(default_factory=list)
    sites: dict[str, Frame] = field(default_factory=dict)
    inertial: Mass | None = None
    children: list[Body] = field(default_factory=list)
    mass: Mass = field(default_factory=Mass.zero)  # own, in the body frame


class Tree:
    """Reads the bodies of `<worldbody>` (the world is bodies[0])."""

    def __init__(self, reader: Reader, defaults: Defaults, compiler: Compiler):
        self.reader, self.defaults, self.compiler = reader, defaults, compiler
        worldbody = reader.root.findall("worldbody")
        world_element = worldbody[0] if worldbody else reader.root
        self.world = Body("world", world_element, None, IDENTITY)
        self.bodies = [self.world]
        self.joints: list[Joint] = []
        for element in worldbody:
            self._walk(element, self.world, IDENTITY, None)
        for body in self.bodies:
            body.mass = self._mass(body)
        for body in self.bodies[1:]:  # compiler boundmass: a lower bound on each body's mass
            if body.mass.mass < compiler.boundmass:
                body.mass = Mass(compiler.boundmass, body.mass.centre, body.mass.tensor)
        total = sum(body.mass.mass for body in self.bodies)
        if compiler.settotalmass > 0 and total > 0:  # MuJoCo scales masses and inertias
            scale = compiler.settotalmass / total
            for body in self.bodies:
                body.mass = Mass(body.mass.mass * scale, body.mass.centre,
                                 body.mass.tensor * scale)

    def _walk(self, element: Element, body: Body, offset: Frame, childclass: str | None):
        for child in element.children:
            path = f"body[{body.name}]"
            if child.tag == "body":
                self._body(child, body, offset, childclass)
            elif child.tag == "frame":
                inner = self.defaults.childclass(child, childclass, f"{path}.frame")
                at = frame(self.reader, child, child.attrib, f"{path}.frame", self.compiler)
                self._walk(child, body, offset * at, inner)
            elif child.tag in ("joint", "freejoint"):
                self._joint(child, body, offset, childclass)
            elif child.tag == "geom":
                self._geom(child, body, offset, childclass)
            elif child.tag == "site":
                attrib = self.defaults.attributes(child, childclass, f"{path}.site")
                placed = fromto(self.reader, child, attrib, f"{path}.site")
                at = placed[0] if placed else frame(self.reader, child, attrib, f"{path}.site",
                                                    self.compiler)
                body.sites[child.attrib.get("name", f"site{len(body.sites)}")] = offset * at
            elif child.tag == "inertial":
                at = frame(self.reader, child, child.attrib, f"{path}.inertial", self.compiler)
                body.inertial = inertial(self.reader, child, offset * at, f"{path}.inertial")
            elif child.tag not in QUIET:
                self.reader.warn(child, path, f"<{child.tag}> not translated")

    def _body(self, element: Element, parent: Body, offset: Frame, childclass: str | None):
        name = element.attrib.get("name", f"body{len(self.bodies)}")
        path = f"body[{name}]"
        inner = self.defaults.childclass(element, childclass, path)
        local = offset * frame(self.reader, element, element.attrib, path, self.compiler)
        body = Body(name, element, parent, local, inner)
        parent.children.append(body)
        self.bodies.append(body)
        for key in ("gravcomp",):
            if float(element.attrib.get(key, "0") or 0) != 0:
                self.reader.warn(element, f"{path}.{key}", f"{key} not translated")
        self._walk(element, body, IDENTITY, inner)

    def _joint(self, element: Element, body: Body, offset: Frame, childclass: str | None):
        path = f"body[{body.name}].joint"
        if body is self.world:
            raise self.reader.error(element, path, "a joint in <worldbody> itself",
                                    "joints inside <body> elements", code="E103")
        attrib = {"type": "free"} if element.tag == "freejoint" else \
            self.defaults.attributes(element, childclass, path)
        if element.tag == "freejoint":
            attrib.update(element.attrib)
        kind = self.reader.choice(element, attrib, "type", path, JOINT_TYPES, "hinge")
        name = attrib.get("name", f"{body.name}_{kind}{len(body.joints) + 1}"
                          if len(body.joints) else f"{body.name}_joint")
        axis = self.reader.numbers(element, attrib, "axis", path, (3,), (0.0, 0.0, 1.0))
        if kind in ("hinge", "slide") and np.linalg.norm(axis) < 1e-12:
            raise self.reader.error(element, f"{path}.axis", "the joint axis is zero",
                                    "a non-zero direction", code="E404")
        axis = offset.rotation @ (axis / (np.linalg.norm(axis) or 1.0))
        pos = offset.point(self.reader.numbers(element, attrib, "pos", path, (3,), (0, 0, 0)))
        angle = self.compiler.angle if kind == "hinge" else float
        ref = angle(self.reader.number(element, attrib, "ref", path, 0.0))
        springref = angle(self.reader.number(element, attrib, "springref", path, 0.0))
        joint = Joint(name, kind, element, attrib, pos, axis, ref, springref, body)
        body.joints.append(joint)
        self.joints.append(joint)

    def _geom(self, element: Element, body: Body, offset: Frame, childclass: str | None):
        path = f"body[{body.name}].geom"
        attrib = self.defaults.attributes(element, childclass, path)
        kind = self.reader.choice(element, attrib, "type", path, GEOM_TYPES, "sphere")
        size = self.reader.numbers(element, attrib, "size", path, (1, 2, 3), (0.0,))
        placed = fromto(self.reader, element, attrib, path) \
            if kind in ("capsule", "cylinder", "box", "ellipsoid") else None
        if placed is not None:
            at, half = placed
            size = np.array([size[0], half]) if kind in ("capsule", "cylinder") else \
                np.array([size[0], size[1] if size.size > 1 else size[0], half])
        else:
            at = frame(self.reader, element, attrib, path, self.compiler)
        need = SIZES.get(kind, 0)
        if kind not in ("mesh", "plane", "hfield", "sdf") and (size.size < need
                                                                or np.any(size[:need] <= 0)):
            raise self.reader.error(element, f"{path}.size", f"a {kind} geom needs {need} "
                                    "positive size numbers", f"size=\"{' '.join(['0.1'] * need)}\"",
                                    code="E410", got=" ".join(f"{v:g}" for v in size))
        name = attrib.get("name", f"{body.name}_geom{len(body.geoms) + 1}")
        body.geoms.append(Geom(name, kind, element, attrib, size[:need] if need else size,
                               offset * at))

    def _mass(self, body: Body) -> Mass:
        """A body's own mass properties (in its frame), per compiler inertiafromgeom."""
        mode = self.compiler.inertiafromgeom
        if body is self.world:
            return Mass.zero()
        if body.inertial is not None and (mode == "false" or mode == "auto"):
            return body.inertial
        if mode == "false":
            return Mass.zero()
        low, high = self.group_range()
        parts = []
        for geom in body.geoms:
            group = int(self.reader.number(geom.element, geom.attrib, "group",
                                           f"body[{body.name}].geom", 0.0))
            if low <= group <= high:
                part = geom_mass(self.reader, geom.element, geom.attrib, geom.kind, geom.size,
                                 geom.at, f"body[{body.name}].geom[{geom.name}]")
                parts.append(part) if part is not None else None
        return combine(parts)

    def group_range(self) -> tuple[int, int]:
        for element in self.reader.root.findall("compiler"):
            values = self.reader.numbers(element, element.attrib, "inertiagrouprange",
                                         "compiler", (2,))
            if values is not None:
                return int(values[0]), int(values[1])
        return 0, 5
