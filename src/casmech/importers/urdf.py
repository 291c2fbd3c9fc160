"""URDF robot description (.urdf) -> casmech model (an `Imported`, written by emit.to_yaml).

Translated:
- the root link is the ground (or, with `floating_base`, a free body); a link joined by a
  `fixed` joint is merged into its parent's body (masses, centres of mass and inertias
  combined; its visuals kept), as MuJoCo's URDF import does (fusestatic); so is a link below
  which nothing has mass (its joint locked at its initial value), and massless intermediate
  links are merged into the joints around them (importers/urdf_groups.py);
- every other link is a body: its frame's axes are the body's axes, its origin the combined
  centre of mass; mass and inertia from `inertial` (rotated from the inertial frame into the link
  frame; checked as casmech checks them, errors at the URDF's line, importers/inertia_check.py);
  `visual` box, cylinder, sphere and mesh become `geometry` (meshes found by
  importers/mesh_paths.py);
- joints: revolute and continuous -> revolute, prismatic -> translational, planar -> planar
  (axis = the plane's normal), floating -> none (a free body); placed at the initial pose;
  a chain through massless links -> the joint it amounts to (importers/joint_chains.py);
- `dynamics damping` -> an rsda (revolute) or a tsda along the axis (prismatic) with that damping;
  `dynamics friction` -> the joint's Coulomb `friction:` (docs/forces.md, joint friction);
- `limit` lower and upper of a revolute or prismatic joint -> the joint's `limit:` stop
  (importers/urdf_limits.py: bounds from the imported pose, MuJoCo's default softness);
  effort and velocity limits, and the limits of joints merged through massless links, are
  comments.
- `mimic` -> a coupler of the two joints (importers/urdf_mimic.py).
Not translated (a warning naming the line): `calibration`, `safety_controller`,
`transmission`, `gazebo` and other extensions; `collision` elements are skipped (a URDF names
no contact pairs or contact laws). URDF has no gravity: the model gets [0, 0, -9.81].

The initial pose is the one at the joint values `positions` (default 0, the URDF's reference
pose) with joint rates `velocities` (default 0); casmech's joint angles are measured from it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from casmech.core.quaternions import from_matrix
from casmech.errors import UsageError, did_you_mean
from casmech.importers import inertia_check, urdf_limits, urdf_mimic
from casmech.importers.adm_frames import tidy
from casmech.importers.emit import Imported, Item, identifier
from casmech.importers.joint_chains import BodyFrame, Elementary, basic_rows, compose, name_of
from casmech.importers.mesh_paths import MeshPaths
from casmech.importers.urdf_geometry import geometry_items
from casmech.importers.urdf_groups import Group, Plan, plan
from casmech.importers.urdf_read import Reader
from casmech.importers.urdf_tree import MOVING, Joint, State, Tree, pose, read_tree

GRAVITY = [0.0, 0.0, -9.81]
DAMPER_LENGTH = 1.0  # [m] distance between the two points of a prismatic joint's damper
SKIPPED = {"collision"}  # link children skipped without a warning (said in the header)
KNOWN = {"robot": {"link", "joint", "material"}, "link": {"inertial", "visual", "collision"},
         "joint": {"parent", "child", "origin", "axis", "limit", "dynamics", "mimic"}}
HINTS = {"transmission": "actuation: add motors or forces by hand (docs/motors.md)"}
ELEMENTARY = {"revolute": "hinge", "continuous": "hinge", "prismatic": "slide"}


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
    def __init__(self, reader: Reader, tree: Tree, state: State, layout: Plan,
                 meshes: MeshPaths, repair: inertia_check.Repair):
        self.reader, self.tree, self.state, self.plan = reader, tree, state, layout
        self.meshes, self.repair = meshes, repair
        self.model = Imported(name=reader.root.attrib.get("name", "robot"), description="",
                              header=[])
        self.groups = layout.groups
        self.names = Names()
        self.body_names = {tree.root: "ground"}  # head link -> casmech body
        self.frames: dict[str, BodyFrame] = {}  # casmech body -> its frame at the pose
        self.positions: dict[str, float] = {}  # URDF joint -> its initial value
        self.single_names: dict[str, str] = {}  # URDF joint -> casmech joint (single joints)

    def warn_unknown(self, element, path: str, kind: str) -> None:
        for child in element.children:
            if child.tag not in KNOWN[kind] and child.tag not in SKIPPED:
                self.reader.warn(child, path, f"<{child.tag}> not translated",
                                 hint=HINTS.get(child.tag))

    def body(self, group: Group) -> None:
        reader, link = self.reader, self.tree.links[group.head]
        path = f"link[{link.name}]"
        mass, centre, inertia = group.mass_properties()
        if mass <= 0:  # only the root can be massless here (a floating base)
            raise reader.error(link.element, path, f"the root link '{link.name}' has no mass "
                               "(with its fixed children): it cannot be a free body",
                               "an <inertial> with a <mass value> > 0", code="E400",
                               hint="import without --floating-base: the root is the ground")
        frame = self.state.frames[link.name]
        omega = self.state.omega[link.name]
        position = frame.point(centre)
        velocity = self.state.velocity[link.name] + np.cross(omega, position - frame.origin)
        name = self.names(link.name, "_link")
        self.body_names[link.name] = name
        self.frames[name] = BodyFrame(frame.rotation, position)
        data = {"name": name, "mass": mass, "inertia": self.inertia(group, inertia, path),
                "position": tidy(position)}
        if not np.allclose(frame.rotation, np.eye(3), rtol=0, atol=1e-15):
            data["orientation"] = {"euler_parameters": tidy(from_matrix(frame.rotation))}
        if np.any(velocity):
            data["velocity"] = tidy(velocity)
        if np.any(omega):
            data["angular_velocity"] = tidy(omega)
        shapes = geometry_items(reader, group.members, centre, self.meshes)
        if shapes:
            data["geometry"] = shapes
        comments = [f"link {link.name} (line {link.element.line}); body axes = the link frame's"]
        comments += [f"link {j.child} (line {self.tree.links[j.child].element.line}) merged in "
                     f"by the {'fixed' if j.type == 'fixed' else 'locked'} joint {j.name} "
                     f"(line {j.element.line})" for j in group.fused]
        for member, _ in group.members:
            self.warn_unknown(member.element, f"link[{member.name}]", "link")
        self.model.bodies.append(Item(data, comments))

    def inertia(self, group: Group, tensor: np.ndarray, path: str) -> list[float]:
        """The six numbers written, checked (and repaired when asked) at the URDF's line."""
        link = next((m for m, _ in group.members if m.inertial is not None
                     and m.inertial.mass > 0), self.tree.links[group.head])
        element = link.element.find("inertial") or link.element
        element = element.find("inertia") or element
        tensor, change = inertia_check.repaired(tensor, self.repair)
        if change:
            self.reader.warn(element, f"{path}.inertial", f"inertia repaired: {change}",
                             code="E401")
        values = self._six(tensor)
        problem = inertia_check.problem(_matrix(values))
        if problem:
            code, message, got = problem
            merged = f" (link {group.head} with {len(group.members) - 1} merged links)" \
                if len(group.members) > 1 else ""
            raise self.reader.error(element, f"link[{link.name}].inertial", message + merged,
                                    "a positive definite inertia whose principal moments "
                                    "satisfy the triangle inequality", code=code, got=got,
                                    hint=inertia_check.HINT)
        return values[:3] if not any(values[3:]) else values

    @staticmethod
    def _six(tensor: np.ndarray) -> list[float]:
        scale = np.max(np.abs(tensor))
        (xx, xy, xz), (_, yy, yz), (_, _, zz) = tensor
        return tidy([xx, yy, zz, xy, xz, yz], scale)

    def joint(self, head: str) -> None:
        chain = self.plan.chains[head]
        body_i = self.body_names[self.plan.parents[head]]
        body_j = self.body_names[head]
        for joint in chain:
            self.warn_unknown(joint.element, f"joint[{joint.name}]", "joint")
        if len(chain) == 1 and chain[0].type == "floating":
            self.model.trailer.append(f"joint {chain[0].name} (line {chain[0].element.line}) "
                                      f"is floating: {body_j} is a free body")
            return
        if len(chain) == 1:
            return self.single(chain[0], body_i, body_j)
        self.composite(chain, body_i, body_j)

    def single(self, joint: Joint, body_i: str, body_j: str) -> None:
        path = f"joint[{joint.name}]"
        name = self.names(joint.name, "_joint")
        frame = self.state.frames[joint.child]
        axis = frame.rotation @ joint.axis
        data = {"name": name, "type": MOVING[joint.type], "body_i": body_i, "body_j": body_j,
                "at": tidy(frame.origin), "axis": tidy(axis)}
        comments = [f"{joint.type} joint {joint.name} (line {joint.element.line})"]
        comments += self.limit(joint, path, data, joint.child)
        comments += self.friction(joint, path, data)
        self.model.joints.append(Item(data, comments))
        self.single_names[joint.name] = name
        self.damper(joint, path, data)

    def mimics(self) -> None:
        """Every <mimic> as a coupler, after the joints (importers/urdf_mimic.py)."""
        known = [joint.name for joint in self.tree.joints]
        for joint in self.tree.joints:
            element = joint.element.find("mimic")
            if element is not None:
                item = urdf_mimic.coupler(self.reader, self.names, self.single_names,
                                          self.positions, joint, element, known)
                if item is not None:
                    self.model.joints.append(item)

    def composite(self, chain: list[Joint], body_i: str, body_j: str) -> None:
        """Joints through massless links, composed into the one joint they amount to."""
        first = chain[0]
        elementary = []
        for joint in chain:
            frame = self.state.frames[joint.child]
            elementary.append(Elementary(ELEMENTARY.get(joint.type, joint.type),
                                         frame.rotation @ joint.axis, frame.origin, joint.name))
        scale = max(1.0, max(float(np.max(np.abs(e.point))) for e in elementary))
        composed = compose(elementary, scale)
        names = ", ".join(f"{j.name} ({j.type}, line {j.element.line})" for j in chain)
        if composed is None:
            massless = self.tree.links[first.child]
            raise self.reader.error(massless.element, f"link[{massless.name}]",
                                    f"link '{massless.name}' has no mass and the joints through "
                                    f"it ({names}) amount to no casmech joint",
                                    "massless links between hinges whose axes meet (universal, "
                                    "spherical), a hinge and a slide on one line (cylindrical), "
                                    "two slides and a normal hinge (planar), or slides only",
                                    code="E400", hint="give the link an <inertial> with a mass")
        comments = [f"joints {names} through massless links, as one joint"]
        for joint in chain:
            comments += self.limit(joint, f"joint[{joint.name}]")
            if joint.element.find("dynamics") is not None:
                self.reader.warn(joint.element.find("dynamics"), f"joint[{joint.name}].dynamics",
                                 "dynamics of a joint merged with others not translated "
                                 "(its coordinate is not one of casmech's joint)", code="E101")
        name = self.names(name_of([j.name for j in chain], f"{body_j}_joint"), "_joint")
        if composed["type"] != "basic":
            data = {"name": name, "body_i": body_i, "body_j": body_j, **composed}
            self.model.joints.append(Item(data, comments))
            return
        rows = basic_rows(composed, self.frames.get(body_i, _GROUND), self.frames[body_j])
        for k, row in enumerate(rows):
            data = {"name": self.names(f"{name}_{k + 1}", "_joint"), "type": row.pop("type"),
                    "body_i": body_i, **{key: v for key, v in row.items() if key.endswith("_i")},
                    "body_j": body_j, **{key: v for key, v in row.items() if key.endswith("_j")}}
            self.model.joints.append(Item(data, comments if k == 0 else []))

    def limit(self, joint: Joint, path: str, data: dict | None = None,
              head: str | None = None) -> list[str]:
        """The comment of a joint's <limit>; with the joint's `data` (a single joint), its
        lower and upper bounds become the joint's `limit:` stop (importers/urdf_limits.py)."""
        element = joint.element.find("limit")
        if element is None or joint.type not in ("revolute", "prismatic", "continuous"):
            return []
        units = dict(zip(("lower", "upper", "effort", "velocity"), (
            ("m", "m", "N", "m/s") if joint.type == "prismatic" else
            ("rad", "rad", "N m", "rad/s")), strict=True))
        value = {key: self.reader.number(element, f"{path}.limit", key)
                 for key in units if key in element.attrib}
        text = ", ".join(f"{key} {value[key]:g} {units[key]}" for key in units if key in value)
        why = urdf_limits.unbounded(joint, value, self.positions.get(joint.name, 0.0))
        if data is None or why:
            return [f"URDF limit (line {element.line}): {text}; not enforced"
                    + (f" ({why})" if why else "")]
        at, axis = np.asarray(data["at"], float), np.asarray(data["axis"], float)
        inertia = urdf_limits.moved_inertia(self.plan, self.state, head, at,
                                            axis / np.linalg.norm(axis),
                                            joint.type == "prismatic")
        data["limit"] = urdf_limits.stop(joint, value["lower"], value["upper"],
                                         self.positions.get(joint.name, 0.0), inertia)
        rest = ", ".join(f"{key} {value[key]:g} {units[key]}" for key in ("effort", "velocity")
                         if key in value)
        return [f"URDF limit (line {element.line}): {text}; lower and upper as the stop "
                f"`limit:` (MuJoCo's default softness: time constant "
                f"{urdf_limits.TIME_CONSTANT:g} s, critically damped)"
                + (f"; {rest} not enforced" if rest else "")]

    def friction(self, joint: Joint, path: str, data: dict) -> list[str]:
        """`dynamics friction` (dry friction along the joint's coordinate, as MuJoCo's URDF
        import reads it into frictionloss) -> the joint's Coulomb `friction:`, its comment."""
        element = joint.element.find("dynamics")
        if element is None or "friction" not in element.attrib:
            return []
        value = self.reader.number(element, f"{path}.dynamics", "friction", 0.0)
        if value < 0:
            raise self.reader.error(element, f"{path}.dynamics", f"friction {value:g} is "
                                    "negative", "a dry friction force or torque >= 0",
                                    code="E103", hint="URDF's friction is the joint's Coulomb "
                                    "friction: N m (revolute) or N (prismatic)")
        if not value:
            return []
        data["friction"] = {"coulomb": value}
        unit = "N" if joint.type == "prismatic" else "N m"
        return [f"dynamics friction of joint {joint.name} (line {element.line}): Coulomb "
                f"friction {value:g} {unit}, static limit the same"]

    def damper(self, joint: Joint, path: str, data: dict) -> None:
        element = joint.element.find("dynamics")
        damping = self.reader.number(element, f"{path}.dynamics", "damping", 0.0) \
            if element is not None else 0.0
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


_GROUND = BodyFrame(np.eye(3), np.zeros(3))


def _matrix(values: list[float]) -> np.ndarray:
    xx, yy, zz, xy, xz, yz = values
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def _check_values(tree: Tree, values: dict[str, float], what: str, locked: set[str]) -> None:
    movable = [j.name for j in tree.joints if j.type in ("revolute", "continuous", "prismatic")]
    for name, value in values.items():
        if name not in movable:
            raise UsageError(f"initial joint {what}: '{name}' is not a revolute, continuous or "
                             f"prismatic joint of the robot"
                             + (f"; {did_you_mean(name, movable)}" if did_you_mean(name, movable)
                                else f"; joints: {', '.join(movable)}"))
        if not np.isfinite(value):
            raise UsageError(f"initial joint {what} of '{name}' is not a finite number")
        if what == "velocity" and value and name in locked:
            raise UsageError(f"initial joint velocity of '{name}': the joint is locked "
                             "(nothing below it has mass), it cannot move")


def import_urdf(path: Path, positions: dict[str, float] | None = None,
                velocities: dict[str, float] | None = None, *, floating_base: bool = False,
                mesh_dirs=(), output: Path | None = None, bound_inertia: float = 0.0,
                balance_inertia: bool = False) -> Imported:
    """The casmech model of a URDF file, posed at the joint `positions` [rad or m] with joint
    `velocities` [rad/s or m/s] (by URDF joint name; default 0). `floating_base`: the root
    link is a free body instead of the ground. Meshes are looked for in `mesh_dirs` too and
    named relative to the folder of `output` (default: the URDF's). `bound_inertia`,
    `balance_inertia`: importers/inertia_check.py."""
    path = Path(path)
    reader = Reader.read(path)
    tree = read_tree(reader)
    positions, velocities = dict(positions or {}), dict(velocities or {})
    _check_values(tree, positions, "position", set())
    layout = plan(reader, tree, positions)
    _check_values(tree, velocities, "velocity", {j.name for j in layout.locked})
    inside = {j.child for j in layout.locked}
    for joint in (j for j in layout.locked if j.parent not in inside):  # the topmost ones
        reader.warn(joint.element, f"joint[{joint.name}]", f"{joint.type} joint "
                    f"'{joint.name}' locked at {positions.get(joint.name, 0.0):g}: nothing "
                    f"below it has mass, so its links are merged into "
                    f"'{layout.groups[joint.parent].head}'", code="E400",
                    hint="give the moving links an <inertial> with a mass to keep the joint")
    meshes = MeshPaths(path, Path(output).parent if output else path.parent,
                       tuple(Path(d) for d in mesh_dirs))
    repair = inertia_check.Repair(bound_inertia, balance_inertia)
    translator = Translator(reader, tree, pose(tree, positions, velocities), layout, meshes,
                            repair)
    translator.positions = positions
    if floating_base:
        translator.body(layout.groups[tree.root])
        translator.model.trailer.append(f"root link {tree.root}: a free body (--floating-base)")
    for head in layout.heads:
        translator.body(layout.groups[head])
    for head in layout.heads:
        translator.joint(head)
    translator.mimics()
    translator.warn_unknown(reader.root, "robot", "robot")
    return _finish(translator, path, positions, velocities, floating_base)


def _finish(translator: Translator, path: Path, positions: dict, velocities: dict,
            floating_base: bool) -> Imported:
    model, tree = translator.model, translator.tree
    ground = translator.groups[tree.root]
    mass = ground.mass_properties()[0]
    if not model.bodies:
        translator.reader.warn(translator.reader.root, "robot", "no link of the robot moves "
                               "(every joint is fixed or locked): the model has no body",
                               code="E103", hint="--floating-base makes the root link a free "
                               "body (a flying or floating robot)")
    model.description = f"URDF robot {model.name} ({path.name})"
    root = (f"Root link {tree.root} is a free body" if floating_base else
            f"Root link {tree.root} is the ground" + (
                f" (with the links fixed to it: {mass:g} kg, not part of the model)"
                if mass > 0 else ""))
    model.header = [f"Imported by `casmech import` from the URDF file {path.name}.",
                    root + "; links joined by fixed joints are merged.",
                    "Body frames: each link's axes at the link's centre of mass. collision "
                    "elements are not translated.",
                    "Initial joint values (URDF joint: position, velocity): " + (", ".join(
                        f"{name}: {positions.get(name, 0.0):g}, {velocities.get(name, 0.0):g}"
                        for name in sorted({*positions, *velocities})) or "all 0") + ".", ""]
    if translator.meshes.folders_outside:
        model.header.insert(-1, "Meshes outside this file's folder are named by absolute "
                            f"paths: allow them with --allow-dir "
                            f"{translator.meshes.common_outside()}")
    model.mesh_folder = translator.meshes.common_outside()
    model.gravity = GRAVITY
    model.gravity_comments = ["URDF has no gravity: the ROS convention, z up"]
    model.warnings = translator.reader.warnings
    return model

