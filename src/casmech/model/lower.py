"""ResolvedModel -> ModelIR: names to indices, joints expanded into primitives.

Composite joints are defined in global coordinates at t = 0; here they become body-frame vectors
using each body's pose in the file (ground: identity).

A model loaded with symbolic parameters (schema.load_model_text's `symbolic`) carries traced
numbers (casmech.core.traced); the same code keeps them, so every number of its IR that
depends on those parameters is a traced number or an object array of them
(model.parametric makes the model data a function of the parameters from it). A plain
model's IR holds floats and float arrays, exactly as without traced numbers.
"""

from __future__ import annotations

import numpy as np

from casmech.core import euler, traced
from casmech.core.last_call import last_call
from casmech.elements import couplings
from casmech.elements.force_types import REGISTRY as FORCE_TYPES
from casmech.elements.joint_types import COORDINATES, REGISTRY
from casmech.model import bindings, initial
from casmech.model.ir import GROUND_INDEX, BodyIR, ForceIR, JointIR, ModelIR, PrimitiveIR, RowInfo
from casmech.schema.resolved import GROUND, Force, Joint, ResolvedModel

# joint-frame quantities that are directions (rotated into a body's frame); every other one
# (P, Q, Pi, Pj, a new entry's point) is a point (moved, then rotated)
DIRECTIONS = frozenset({"u", "v", "w", "axis", "axis_i", "axis_j", "ex", "ey", "ez"})
UNIT = {"ex": np.array([1.0, 0, 0]), "ey": np.array([0, 1.0, 0]), "ez": np.array([0, 0, 1.0])}


def perpendicular_pair(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit u, v with (u, v, w) right-handed orthonormal; deterministic in w."""
    e = np.eye(3)[int(np.argmin(np.abs(w)))]  # the branch at theta0 (traced numbers)
    u = e - (e @ w) * w
    u /= np.linalg.norm(u)
    return u, np.cross(w, u)


class Poses:
    """Initial poses by body name (ground: origin, identity), their indices, the joints by name
    (the helper force_types' `lower` receives)."""

    def __init__(self, model: ResolvedModel):
        self.joints = {j.name: j for j in model.joints}
        self.index = {b.name: k for k, b in enumerate(model.bodies)} | {GROUND: GROUND_INDEX}
        self.pose = {b.name: (b.position, rotation)
                     for b, rotation in zip(model.bodies, _rotations(model.bodies), strict=True)}
        self.pose[GROUND] = (np.zeros(3), np.eye(3))
        self.quaternion = {b.name: traced.asarray(b.euler_parameters) for b in model.bodies}
        self.quaternion[GROUND] = np.array([1.0, 0.0, 0.0, 0.0])

    def local(self, body: str, quantity: str, value: np.ndarray) -> np.ndarray:
        r0, a0 = self.pose[body]
        return a0.T @ value if quantity in DIRECTIONS else a0.T @ (value - r0)

    def joint(self, name: str) -> tuple[Joint, dict[str, np.ndarray]]:
        """A joint by name and its global joint frame at t = 0 (joint_frame)."""
        joint = self.joints[name]
        return joint, joint_frame(joint)


def _rotations(bodies) -> list:
    """Each body's rotation matrix A(p) at its Euler parameters in the file: traced.numeric's,
    by one mapped call over the bodies when none is traced (the same arithmetic per body)."""
    if any(traced.is_traced(b.euler_parameters) for b in bodies) or not bodies:
        return [traced.numeric(euler.rotation, b.euler_parameters) for b in bodies]
    columns = np.column_stack([np.asarray(traced.value(b.euler_parameters), float).reshape(-1)
                               for b in bodies])
    matrices = euler.numeric_columns(euler.rotation, columns)
    return [np.ascontiguousarray(matrices[:, 3 * k:3 * k + 3]) for k in range(len(bodies))]


def joint_frame(joint: Joint) -> dict[str, np.ndarray]:
    """Global joint-frame quantities at t = 0 (casmech.elements.joint_types: the entry's `frame`
    names
    the quantity of each vector key)."""
    v = joint.vectors
    frame = dict(UNIT) | {"u": UNIT["ex"], "v": UNIT["ey"], "w": UNIT["ez"]}  # fixed: no axis
    for key, name in REGISTRY[joint.type].frame.items():
        if key in v and key != "axis":
            frame[name] = traced.asarray(v[key])
    if "axis" in v:
        w = traced.asarray(v["axis"]) / np.linalg.norm(v["axis"])
        frame["u"], frame["v"] = perpendicular_pair(w)
        frame["w"] = w
    constants = REGISTRY[joint.type].constants
    if constants is not None and joint.options:
        frame |= constants(joint.options)
    return frame


def _vectors(template: dict[str, str], joint: Joint, frame, poses: Poses) -> dict:
    out = {}
    for key, spec in template.items():
        name, _, side = spec.partition("@")
        if not side:  # basic constraint: as written in the file
            out[key] = traced.asarray(joint.vectors.get(name, frame.get(name)))
        else:
            body = joint.body_i if side == "i" else joint.body_j
            out[key] = poses.local(body, name, frame[name])
    return out


def _offset(joint: Joint, frame) -> float:
    """The constant part of f for a composite joint's D rows: the squared length (`length`,
    else the entry's arm at t = 0)."""
    arm = REGISTRY[joint.type].arm
    if arm is None:
        return 0.0
    if joint.length is not None:
        return traced.scalar(joint.length) ** 2
    return traced.scalar(np.sum((frame[arm[1]] - frame[arm[0]]) ** 2))


def lower_joint(joint: Joint, poses: Poses, first_row: int) -> tuple[list[PrimitiveIR], JointIR]:
    frame = joint_frame(joint)
    bi, bj = poses.index[joint.body_i], poses.index[joint.body_j]
    entry = REGISTRY[joint.type]
    templates = [(t, joint.f, False) for t in entry.rows]
    templates += [(COORDINATES[key].driver, fun, True) for key, fun in joint.drivers.items()]
    offset = _offset(joint, frame)
    prims = []
    for (kind, template, label), fun, is_driver in templates:
        source = joint.sources.get("driver", joint.source) if is_driver else joint.source
        row = RowInfo(joint.name, kind, f"{joint.type} '{joint.name}': {label}", source)
        prims.append(PrimitiveIR(kind, bi, bj, _vectors(template, joint, frame, poses), fun,
                                 offset if kind == "d" and not is_driver else 0.0, is_driver, row))
    point_name = entry.reaction_point
    if point_name is None:
        point = np.zeros(3) if joint.body_i != GROUND else poses.pose[GROUND][0]
    elif point_name in joint.vectors and point_name.startswith("s_"):
        point = traced.asarray(joint.vectors[point_name])
    else:
        point = poses.local(joint.body_i, point_name, frame[point_name])
    rows = range(first_row, first_row + len(prims))
    drivers = dict(joint.drivers)
    where = {key.removeprefix("initial."): source for key, source in joint.sources.items()
             if key.startswith("initial.")}
    return prims, JointIR(joint.name, joint.type, bi, bj, rows, point, joint.source,
                          _geometry(joint, frame, poses), drivers, joint.cut,
                          joint.reaction_frame, _reaction_point(joint, poses),
                          dict(joint.initial), where)


def lower_coupling(joint: Joint, poses: Poses,
                   first_row: int) -> tuple[list[PrimitiveIR], JointIR]:
    """A coupling's one row over the bodies of the joints it couples (the output joint's
    body_i and body_j first), and its JointIR with the output joint's frames."""
    couples = REGISTRY[joint.type].couples
    coupled = [poses.joint(name) for name, _ in joint.couples]
    output, output_frame = coupled[couples.output]
    bodies = [output.body_i, output.body_j]
    vectors, pattern, slots = {}, "", []
    for k, ((other, frame), (_, coordinate)) in enumerate(zip(coupled, joint.couples,
                                                               strict=True)):
        letter = couplings.LETTER[coordinate]
        pattern += letter
        sides = {"i": other.body_i, "j": other.body_j}
        for side in "ij":
            if sides[side] not in bodies:
                bodies.append(sides[side])
            slots.append(bodies.index(sides[side]))
        for key, where in COORDINATES[coordinate].vectors.items():
            quantity, side = where.split("@")
            vectors[f"{key}{k}"] = poses.local(sides[side], quantity, frame[quantity])
    vectors["c"] = traced.array(list(joint.coefficients)
                                + [0.0] * (3 - len(joint.coefficients)))
    whole = couplings.integers(joint.coefficients) if all(couplings.periodic(pattern)) else None
    kind = couplings.kind(pattern, tuple(slots), whole)
    index = [poses.index[b] for b in bodies]
    label = f"{joint.type} '{joint.name}': {couples.label}"
    prim = PrimitiveIR(kind, index[0], index[1], vectors, None,
                       traced.scalar(joint.options.get("offset", 0.0)),
                       row=RowInfo(joint.name, kind, label, joint.source), others=tuple(index[2:]))
    point = poses.local(output.body_i, "P", output_frame["P"])
    return [prim], JointIR(joint.name, joint.type, index[0], index[1],
                           range(first_row, first_row + 1), point, joint.source,
                           _geometry(output, output_frame, poses), {}, True,
                           joint.reaction_frame, _reaction_point(joint, poses),
                           couples=tuple(joint.couples), coefficients=tuple(joint.coefficients))


FRAME_QUANTITIES = ("P", "u", "v", "w", "axis_i", "axis_j")


def _reaction_point(joint: Joint, poses: Poses) -> np.ndarray | None:
    """`reactions: {point: ...}` (global at t = 0) in body i's frame (ground: global)."""
    if joint.reaction_point is None:
        return None
    return poses.local(joint.body_i, "P", traced.asarray(joint.reaction_point))


def _geometry(joint: Joint, frame, poses: Poses) -> dict[str, np.ndarray]:
    """The joint frame's quantities in both bodies' frames, "<name>@i" and "<name>@j"; for a
    type whose states include a relative rotation (`e0`), "q@i" and "q@j": the Euler
    parameters from each body's frame to the joint frame, conj(p) of its pose in the file
    (equations/joint_states.py)."""
    found = {f"{name}@{side}": poses.local(body, name, frame[name])
             for name in FRAME_QUANTITIES if name in frame
             for side, body in (("i", joint.body_i), ("j", joint.body_j))}
    if "e0" in REGISTRY[joint.type].states:
        for side, body in (("i", joint.body_i), ("j", joint.body_j)):
            p = poses.quaternion[body]
            found[f"q@{side}"] = traced.array([p[0], -p[1], -p[2], -p[3]])
    return found


def joint_coordinates(joint: Joint, poses: Poses) -> ForceIR:
    """Geometry of a joint's coordinates (equations/coordinates.py), 0 at the file's pose: the
    joint frame's u, v, w on body_i, u on body_j (as an rsda's), the joint point on both, and
    the further directions the registered coordinate kinds' measures read."""
    frame = joint_frame(joint)
    axes = {f"{key}_i": poses.local(joint.body_i, key, frame[key]) for key in "uvw"}
    axes["u_j"] = poses.local(joint.body_j, "u", frame["u"])
    sides = {"i": joint.body_i, "j": joint.body_j}
    for kind in COORDINATES.values():  # what further kinds' measures read
        for key, where in kind.vectors.items():
            quantity, side = where.split("@")
            if key not in axes and quantity != "P" and quantity in frame:
                axes[key] = poses.local(sides[side], quantity, frame[quantity])
    points = {f"s_{side}": poses.local(body, "P", frame["P"])
              for side, body in (("i", joint.body_i), ("j", joint.body_j))}
    return ForceIR(joint.name, joint.type, poses.index[joint.body_i], poses.index[joint.body_j],
                   points, {}, axes=axes, source=joint.source)


def lower_force(force: Force, model: ResolvedModel, poses: Poses) -> ForceIR:
    """A force element, lowered by its casmech.elements.force_types entry."""
    fields = FORCE_TYPES[force.type].lower(force, model, poses)
    return ForceIR(force.name, force.type, **fields, source=force.source)


# the last model lowered and its IR: a run lowers its model twice (backends.codegen.auto_mode
# looks its library up, then backends.compile builds its functions); both are frozen records
_last = last_call(lambda model: _lowered(model))


def lower(model: ResolvedModel) -> ModelIR:
    """The model's IR (the same IR again for the model lowered last)."""
    return _last(model)


def _lowered(model: ResolvedModel) -> ModelIR:
    poses = Poses(model)
    primitives: list[PrimitiveIR] = []
    joints: list[JointIR] = []
    for joint in model.joints:
        lowering = lower_coupling if REGISTRY[joint.type].couples else lower_joint
        prims, joint_ir = lowering(joint, poses, len(primitives))
        primitives += prims
        joints.append(joint_ir)
    bodies = tuple(
        BodyIR(b.name, traced.scalar(b.mass), traced.asarray(b.inertia),
               traced.asarray(b.position), traced.asarray(b.euler_parameters),
               traced.asarray(b.velocity), traced.asarray(b.angular_velocity), b.source)
        for b in model.bodies
    )
    posed = initial.posed_bodies(model, bodies, {j.name: joint_frame(j) for j in model.joints})
    reference = None if posed is bodies else traced.array(
        [x for b in bodies for x in b.r0] + [x for b in bodies for x in b.p0])
    geometry = {j.name: bindings.coordinate_geometry(j) for j in joints
                if bindings.has_coordinates(j.type)}  # for force laws reading the state
    forces = tuple(bindings.bind(lower_force(f, model, poses), poses.index, geometry)
                   for f in model.forces)
    effort = tuple(m for j in model.joints if j.motor
                   for m in bindings.motors(j, joint_frame(j), poses))
    stops = tuple(bindings.stop(j, geometry[j.name]) for j in model.joints
                  if j.limit)
    stops += tuple(bindings.friction(j, geometry[j.name]) for j in model.joints if j.friction)
    return ModelIR(model.name, model.file, model.text, posed, tuple(primitives), tuple(joints),
                   forces, traced.asarray(model.gravity), model.analysis, dict(model.parameters),
                   motors=effort, limits=stops, outputs=tuple(model.outputs),
                   reference_pose=reference)
