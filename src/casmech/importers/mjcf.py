"""MuJoCo MJCF model (.xml) -> casmech model (an `Imported`, written by emit.to_yaml).

Translated (docs/import.md has the table):
- bodies: every body with joints is a casmech body (axes: the MJCF body frame's; origin: the
  centre of mass of it and of the bodies welded to it, which are merged in, as MuJoCo's
  fusestatic does); bodies without joints under the world are the ground; mass properties from
  `<inertial>` or the geoms (importers/mjcf_inertia.py), checked as casmech checks them, with
  errors at the MJCF line (`compiler boundinertia` / `balanceinertia` or the command's options
  repair them);
- joints: hinge -> revolute, slide -> translational, ball -> spherical, free -> none (a free
  body); several joints in one body -> the casmech joint they amount to
  (importers/joint_chains.py: a gimbal of hinges -> spherical, two perpendicular hinges ->
  universal, hinge + slide on a line -> cylindrical, two slides + normal hinge -> planar);
- a single hinge's `stiffness`, `springref` and `damping` -> an rsda (exact: MuJoCo's passive
  force -k (q - springref) - d q_dot); a single slide's -> a tsda along the axis (exact while
  the slide stays above -1 m); `armature` (reflected rotor inertia on the joint's diagonal of
  the mass matrix), `frictionloss`, and the passive terms of balls, free joints and joints
  merged into one are not translated (a warning naming the line); `range` is a comment;
- geoms -> geometry items and contact elements (importers/mjcf_geoms.py), actuators -> effort
  motors (importers/mjcf_actuators.py), `connect` / `weld` equalities -> spherical / fixed
  joints closing loops (importers/mjcf_equality.py), `default` classes, `include`, compiler
  angle units and Euler sequences (importers/mjcf_defaults.py, mjcf_read.py), `option
  gravity`, a keyframe as the initial state (importers/mjcf_state.py).
Anything else is a warning naming its file and line, and what changes the physics is kept as a
comment at the end of the YAML.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from casmech.core.quaternions import from_matrix
from casmech.importers import inertia_check, mjcf_actuators, mjcf_assets
from casmech.importers.adm_frames import tidy
from casmech.importers.emit import Imported, Item
from casmech.importers.joint_chains import BodyFrame, Elementary, basic_rows, compose, name_of
from casmech.importers.mesh_paths import MeshPaths
from casmech.importers.mjcf_bodies import Body, Tree
from casmech.importers.mjcf_defaults import Defaults, compiler
from casmech.importers.mjcf_equality import loops
from casmech.importers.mjcf_frames import Frame
from casmech.importers.mjcf_geoms import contacts, geometry_items
from casmech.importers.mjcf_inertia import combine
from casmech.importers.mjcf_read import Reader
from casmech.importers.mjcf_state import State, initial_state
from casmech.importers.urdf import DAMPER_LENGTH, Names

TYPES = {"hinge": "revolute", "slide": "translational", "ball": "spherical"}


class Translator:
    def __init__(self, reader: Reader, path: Path, options: dict):
        self.reader, self.path = reader, path
        self.compiler = compiler(reader)
        self.defaults = Defaults(reader)
        self.tree = Tree(reader, self.defaults, self.compiler)
        self.model = Imported(name=reader.root.attrib.get("model", path.stem), description="",
                              header=[])
        self.names = Names()
        self.repair = inertia_check.Repair(
            max(options.get("bound_inertia", 0.0), self.compiler.boundinertia),
            options.get("balance_inertia", False) or self.compiler.balanceinertia)
        output = options.get("output")
        self.meshes = MeshPaths(path, Path(output).parent if output else path.parent,
                                tuple(Path(d) for d in options.get("mesh_dirs", ())))
        self.assets = mjcf_assets.meshes(reader, self.defaults, self.compiler, path)
        count = sum(len(block.children) for block in reader.root.findall("actuator"))
        self.state: State = initial_state(reader, self.tree, options.get("keyframe"),
                                          dict(options.get("positions") or {}),
                                          dict(options.get("velocities") or {}), count)
        self.head = {self.tree.world: self.tree.world}
        for body in self.tree.bodies[1:]:
            self.head[body] = body if body.joints else self.head[body.parent]
        self.heads = [b for b in self.tree.bodies[1:] if b.joints]
        self.body_names = {self.tree.world: "ground"}
        self.masses: dict[Body, float] = {}
        self.joint_names: dict[str, tuple[str, str]] = {}  # MJCF joint -> (casmech joint, type)

    def members(self, head: Body) -> list[tuple[Body, Frame]]:
        """The MJCF bodies of a casmech body, with their frames in the head's frame."""
        inverse = _inverse(self.state.frames[head])
        return [(b, inverse * self.state.frames[b]) for b in self.tree.bodies
                if self.head[b] is head]

    # ------------------------------------------------------------------------ bodies
    def body(self, head: Body) -> None:
        path = f"body[{head.name}]"
        members = self.members(head)
        mass = combine([b.mass.placed(at) for b, at in members])
        if mass.mass <= 0:
            raise self.reader.error(head.element, path, f"body '{head.name}' moves (it has "
                                    "joints) but has no mass (with the bodies welded to it)",
                                    "an <inertial> with mass > 0, or geoms with mass",
                                    code="E400", hint="MuJoCo refuses such a body too")
        frame = self.state.frames[head]
        omega = self.state.omega[head]
        position = frame.point(mass.centre)
        velocity = self.state.velocity[head] + np.cross(omega, position - frame.origin)
        name = self.names(head.name, "_body")
        self.body_names[head], self.masses[head] = name, mass.mass
        data = {"name": name, "mass": mass.mass, "inertia": self.inertia(head, mass.tensor),
                "position": tidy(position)}
        if not np.allclose(frame.rotation, np.eye(3), rtol=0, atol=1e-15):
            data["orientation"] = {"euler_parameters": tidy(from_matrix(frame.rotation))}
        if np.any(velocity):
            data["velocity"] = tidy(velocity)
        if np.any(omega):
            data["angular_velocity"] = tidy(omega)
        shapes = geometry_items(self.reader, members, mass.centre, self.meshes, self.assets)
        if shapes:
            data["geometry"] = shapes
        comments = [f"body {head.name} (line {head.element.line}); body axes = its frame's"]
        comments += [f"body {b.name} (line {b.element.line}) welded to it, merged in"
                     for b, _ in members[1:]]
        self.model.bodies.append(Item(data, comments))

    def inertia(self, head: Body, tensor: np.ndarray) -> list[float]:
        where = next((b.element.find("inertial") for b, _ in self.members(head)
                      if b.element.find("inertial") is not None), None) or head.element
        tensor, change = inertia_check.repaired(tensor, self.repair)
        if change:
            self.reader.warn(where, f"body[{head.name}]", f"inertia repaired: {change}",
                             code="E401")
        scale = np.max(np.abs(tensor))
        (xx, xy, xz), (_, yy, yz), (_, _, zz) = tensor
        values = tidy([xx, yy, zz, xy, xz, yz], scale)
        xx, yy, zz, xy, xz, yz = values
        problem = inertia_check.problem(np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]))
        if problem:
            code, message, got = problem
            raise self.reader.error(where, f"body[{head.name}].inertial", message,
                                    "a positive definite inertia whose principal moments "
                                    "satisfy the triangle inequality", code=code, got=got,
                                    hint=inertia_check.HINT)
        return values[:3] if not any(values[3:]) else values

    # ------------------------------------------------------------------------ joints
    def joint(self, head: Body) -> None:
        parent = self.head[head.parent]
        body_i, body_j = self.body_names[parent], self.body_names[head]
        joints = head.joints
        lines = ", ".join(f"{j.name} ({j.kind}, line {j.element.line})" for j in joints)
        if any(j.kind == "free" for j in joints):
            if len(joints) > 1:
                raise self.reader.error(joints[0].element, f"body[{head.name}]", "a free joint "
                                        "with other joints in one body", "a free joint alone",
                                        code="E103")
            self.model.trailer.append(f"free joint {joints[0].name} (line "
                                      f"{joints[0].element.line}): {body_j} is a free body")
            self.passive_not_translated(joints[0])
            return
        elementary = [Elementary(j.kind, *self.state.axes[j], j.name) for j in joints]
        scale = max(1.0, float(np.max(np.abs(self.state.frames[head].origin))))
        composed = compose(elementary, scale)
        if composed is None:
            raise self.reader.error(joints[0].element, f"body[{head.name}]", f"the joints of "
                                    f"body '{head.name}' ({lines}) amount to no casmech joint",
                                    "one joint, hinges meeting in a point (universal, "
                                    "spherical), a hinge and a slide on one line, two slides "
                                    "and a normal hinge, or slides only", code="E103",
                                    hint="split the body, or join it by hand in the YAML")
        name = self.names(name_of([j.name for j in joints], f"{head.name}_joint"), "_joint")
        comments = [f"joint{'s' if len(joints) > 1 else ''} {lines}"]
        comments += [self.range_comment(j) for j in joints if "range" in j.attrib]
        if composed["type"] == "basic":
            frames = {b: BodyFrame(self.state.frames[h].rotation, self.centre(h))
                      for b, h in ((body_i, parent), (body_j, head))}
            for k, row in enumerate(basic_rows(composed, frames[body_i], frames[body_j])):
                data = {"name": self.names(f"{name}_{k + 1}", "_joint"), "type": row.pop("type"),
                        "body_i": body_i, **{a: v for a, v in row.items() if a.endswith("_i")},
                        "body_j": body_j, **{a: v for a, v in row.items() if a.endswith("_j")}}
                self.model.joints.append(Item(data, comments if k == 0 else []))
        else:
            data = {"name": name, "body_i": body_i, "body_j": body_j, **composed}
            self.model.joints.append(Item(data, comments))
            if len(joints) == 1 and joints[0].kind in ("hinge", "slide"):
                self.joint_names[joints[0].name] = (name, composed["type"])
                return self.springs(joints[0], data)
        for joint in joints:
            self.passive_not_translated(joint)

    def centre(self, body: Body) -> np.ndarray:
        if body is self.tree.world:
            return np.zeros(3)
        mass = combine([b.mass.placed(at) for b, at in self.members(body)])
        return self.state.frames[body].point(mass.centre)

    def range_comment(self, joint) -> str:
        values = self.reader.numbers(joint.element, joint.attrib, "range", "joint", (2,))
        unit = "m"
        if joint.kind == "hinge":
            values, unit = [self.compiler.angle(v) for v in values], "rad"
        return (f"MJCF range of {joint.name} (line {joint.element.line}): {values[0]:g} to "
                f"{values[1]:g} {unit}; not enforced (limits are not translated)")

    def _number(self, joint, key: str) -> float:
        return self.reader.number(joint.element, joint.attrib, key, f"joint[{joint.name}]", 0.0)

    def springs(self, joint, data: dict) -> None:
        """A single hinge's or slide's stiffness and damping as an rsda or a tsda."""
        stiffness, damping = self._number(joint, "stiffness"), self._number(joint, "damping")
        for key in ("armature", "frictionloss"):
            if self._number(joint, key):
                self.reader.warn(joint.element, f"joint[{joint.name}].{key}", f"{key} not "
                                 "translated" + (" (reflected inertia on the joint's diagonal"
                                                 " of the mass matrix: no casmech element)"
                                                 if key == "armature" else ""))
        if not stiffness and not damping:
            return
        q0 = float(self.state.qpos[joint][0])
        force = {"name": self.names(f"{data['name']}_spring", "_force")}
        if joint.kind == "hinge":
            force |= {"type": "rsda", "joint": data["name"], "stiffness": stiffness,
                      "free_angle": joint.springref - q0, "damping": damping}
        else:
            far = np.asarray(data["at"]) + DAMPER_LENGTH * np.asarray(data["axis"])
            force |= {"type": "tsda", "body_i": data["body_i"], "at_i": data["at"],
                      "body_j": data["body_j"], "at_j": tidy(far), "stiffness": stiffness,
                      "free_length": DAMPER_LENGTH + joint.springref - q0, "damping": damping}
        comment = [f"stiffness and damping of joint {joint.name} (line {joint.element.line})"]
        self.model.forces.append(Item(force, comment))

    def passive_not_translated(self, joint) -> None:
        for key in ("stiffness", "damping", "armature", "frictionloss"):
            if self._number(joint, key):
                self.reader.warn(joint.element, f"joint[{joint.name}].{key}", f"{key} of a "
                                 f"{joint.kind} joint" + (" merged with others" if len(
                                     joint.body.joints) > 1 else "") + " not translated")

    # ------------------------------------------------------------------------ the rest
    def motors(self) -> None:
        by_joint: dict[str, list[str]] = {}
        for actuator in mjcf_actuators.actuators(self.reader, self.defaults,
                                                 self.compiler.autolimits, self.state.ctrl):
            target = self.joint_names.get(actuator.joint)
            known = [j.name for j in self.tree.joints]
            if actuator.joint not in known:
                from casmech.errors import did_you_mean

                raise self.reader.error(actuator.element, f"actuator[{actuator.name}].joint",
                                        f"unknown joint '{actuator.joint}'", "the name of a "
                                        "<joint>", code="E300", got=actuator.joint,
                                        hint=did_you_mean(actuator.joint, known) or None)
            if target is None:
                self.reader.warn(actuator.element, f"actuator[{actuator.name}]", f"the actuator"
                                 f"'s joint '{actuator.joint}' is not a single casmech revolute "
                                 "or translational joint: not translated")
                continue
            joint, kind = target
            parameter = self.names(f"ctrl_{actuator.name}", "_ctrl")
            self.model.parameters.append((parameter, actuator.ctrl, f"control of actuator "
                                          f"{actuator.name} (line {actuator.element.line}): "
                                          f"{actuator.note}"))
            q0 = float(self.state.qpos[self.mj_joint(actuator.joint)][0])
            coordinate = "angle" if kind == "revolute" else "displacement"
            by_joint.setdefault(joint, []).append(mjcf_actuators.expression(
                actuator, parameter, q0, f"{coordinate}_dot", coordinate))
        for item in self.model.joints:
            if item.data["name"] in by_joint:
                key = "torque" if item.data["type"] == "revolute" else "force"
                item.data["motor"] = {key: " + ".join(by_joint[item.data["name"]])}
                item.comments.append("motor: MuJoCo's actuator force law (docs/import.md)")

    def mj_joint(self, name: str):
        return next(j for j in self.tree.joints if j.name == name)

    def equality(self) -> None:
        named = {b.name: b for b in self.tree.bodies}
        sites = {site: (b, at) for b in self.tree.bodies for site, at in b.sites.items()}
        for loop in loops(self.reader, named, sites, self.state.frames, self.model.trailer):
            body_i, body_j = (self.body_names[self.head[b]] for b in (loop.body_i, loop.body_j))
            if body_i == body_j:
                self.reader.warn(loop.element, f"equality[{loop.name}]", "the two bodies are "
                                 "welded together already: left out")
                continue
            data = {"name": self.names(loop.name, "_loop"), "type": loop.kind,
                    "body_i": body_i, "body_j": body_j, "at": tidy(loop.at)}
            self.model.joints.append(Item(data, [f"equality {loop.element.tag} {loop.name} "
                                                 f"(line {loop.element.line}): a closed loop"]))

    def contact(self, enabled: bool) -> None:
        if not enabled:
            return
        excluded, _ = mjcf_assets.excluded(self.reader)
        planes, moving = [], []
        for body in self.tree.bodies:
            for geom in body.geoms:
                at = self.state.frames[body] * geom.at
                if geom.kind == "plane" and self.head[body] is self.tree.world:
                    planes.append((geom, at, body.name))
                elif self.head[body] is not self.tree.world:
                    head = self.head[body]
                    moving.append((self.body_names[head], self.masses[head], body, geom, at))
        for element, comment in contacts(self.reader, planes, moving, excluded):
            element["name"] = self.names(element["name"], "_contact")
            self.model.forces.append(Item(element, [comment]))


def _inverse(frame: Frame) -> Frame:
    return Frame(frame.rotation.T, -frame.rotation.T @ frame.origin)


def import_mjcf(path: Path, **options) -> Imported:
    """The casmech model of an MJCF file. `options` (all optional): `positions`, `velocities`
    (joint name -> qpos / qvel of a hinge or slide), `keyframe` (a <key>'s name or index),
    `mesh_dirs`, `output` (the YAML's path: meshes are named relative to its folder),
    `bound_inertia`, `balance_inertia` (importers/inertia_check.py)."""
    path = Path(path)
    reader = Reader.read(path)
    mjcf_assets.unknown_sections(reader)
    translator = Translator(reader, path, options)
    gravity, contact, notes = mjcf_assets.option(reader)
    for head in translator.heads:
        translator.body(head)
    for head in translator.heads:
        translator.joint(head)
    translator.motors()
    translator.equality()
    translator.contact(contact)
    model = translator.model
    if not model.bodies:
        reader.warn(reader.root, "mujoco", "no body of the model moves: it has no body",
                    code="E103")
    model.description = f"MuJoCo model {model.name} ({path.name})"
    model.header = [f"Imported by `casmech import` from the MJCF file {path.name}.",
                    "Bodies without joints are merged into their parent (the world's: the "
                    "ground); body frames: each body's axes at its centre of mass.",
                    "Cameras, lights, sites and MuJoCo's solver and viewer settings are not "
                    "translated; geoms in groups 0-2 are drawn.",
                    "Initial state: " + (f"keyframe {options['keyframe']}"
                                         if options.get("keyframe") else "the file's pose")
                    + (", with --position/--velocity" if options.get("positions")
                       or options.get("velocities") else "") + ", at rest unless given.",
                    *notes, ""]
    model.gravity = gravity
    model.gravity_comments = ["option gravity (MuJoCo's default 0 0 -9.81)"]
    model.mesh_folder = translator.meshes.common_outside()
    model.warnings = reader.warnings
    return model
