"""What the HTML player draws besides the bodies: the ground, contact planes, joint frames, force
vectors, trails of points and the mechanism's extent at every frame.

Everything is taken from the model (lowered by model.lower, so joint points and frames are the
ones the constraints use) and from the results columns (docs/format.md, results contract); a
vector whose columns the table lacks is not drawn. Per frame (F frames):

- reactions: `<joint>.fx..fz` is the force on body_j, drawn at the joint point carried by body_i;
  `<joint>.tx..tz` the torque, drawn there too (a torque the table gives about a `reactions:
  point` Q is moved back to the joint point P: T_P = T_Q - (P - Q) x F). Columns in another
  reaction frame (metadata.json `reaction_frames`, else the model's) are turned into global
  components first: v = R v_frame with R of runtime/reaction_frames.py.
- motors: the part of a driven or motored joint's reaction along its axis w (global A_i w_i):
  (T . w) w for an angle driver or torque motor, (F . w) w for a displacement driver or force
  motor; the results contract puts the actuation in the reaction, and about the axis it is all
  of it.
- contacts: `<force>.normal_force` along the contact normal (towards body_j), drawn at the
  contact point P of elements/forces/contact.py; an element of several points (a point set,
  a capsule's two ends) has only its total in the table, drawn at the mean of the points in contact
  weighted by penetration^exponent (the elastic law's share of each). `<force>.friction_force`
  (the magnitude) against the slip there: v_t, the tangential part of v_j(P) - v_i(P) from the
  velocity columns.
- trails: chosen points of bodies (global at t = 0, carried by the body), else every body's CM.
- contact shapes: the spheres, capsules and points each contact element collides with.
- the extent: centre and radius of a sphere holding every part at each frame (the parts'
  convex hulls), for a camera that frames the mechanism at the current time.

The ground plane is the plane of a contact on ground whose normal is against gravity when there
is one, else the plane normal to `up` through the lowest point any part reaches.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from casmech.core.records import record
from casmech.elements.coordinate_kinds import ANGLE, BY_MODE, View
from casmech.elements.coordinate_kinds import REGISTRY as COORDINATES
from casmech.errors import UsageError
from casmech.io.animate import GROUND_INDEX, MARKER, Part, Scene, sphere
from casmech.schema.resolved import ResolvedModel

CONTACTS = ("sphere_plane", "sphere_sphere", "points_plane", "capsule_plane")
# vector kind (an effort motor's: its ForceIR type) -> unit of its length
UNITS = View(lambda: {"force": "N", "torque": "N m", "normal": "N", "friction": "N"}
             | {kind.effort: kind.quantity.effort_unit for kind in COORDINATES.values()})
LEVEL = 0.999  # |n . up| above which a contact plane on ground is the ground


def _motor(drive: str) -> tuple[str, bool]:
    """A driven coordinate kind or an effort motor mode -> (arrow kind: its effort motor's
    ForceIR type, whether it acts about the axis: a torque)."""
    kind = COORDINATES[drive] if drive in COORDINATES else BY_MODE[drive][0]
    return kind.effort, kind.quantity is ANGLE


@record
class Arrow:
    """A vector drawn at every frame: origin and value (F, 3), global; `kind` in UNITS.
    `carrier`: (body, point in its frame) when the origin is a point fixed in a body."""

    kind: str
    name: str
    origin: np.ndarray
    vector: np.ndarray
    carrier: tuple[int, np.ndarray] | None = None


@record
class Triad:
    """A joint's frame u, v, w (columns of axes) at a point, both in body `body`'s frame."""

    name: str
    body: int
    origin: np.ndarray
    axes: np.ndarray


@record
class Plane:
    """A contact plane carried by body `body` (point and unit normal in its frame)."""

    name: str
    body: int
    point: np.ndarray
    normal: np.ndarray


@record
class Trail:
    name: str
    body: int
    points: np.ndarray  # (F, 3) global
    chosen: bool  # asked for (shown at start) rather than a body's CM offered by default


@record
class Overlays:
    shapes: tuple[Part, ...]  # what each contact element collides with, in its body's frame
    arrows: tuple[Arrow, ...]
    triads: tuple[Triad, ...]
    planes: tuple[Plane, ...]
    trails: tuple[Trail, ...]
    ground: tuple[np.ndarray, np.ndarray]  # a point of the ground plane and its normal (up)
    centres: np.ndarray  # (F, 3) centre of the mechanism at each frame
    radii: np.ndarray  # (F,) radius of a sphere holding it there


# ---------------------------------------------------------------------------------- helpers
def _columns(names: Sequence[str], values: np.ndarray, rows: np.ndarray, wanted):
    """The columns `wanted` at the drawn rows (F, len(wanted)), or None if one is missing."""
    index = {name: k for k, name in enumerate(names)}
    if any(name not in index for name in wanted):
        return None
    return values[np.ix_(rows, [index[name] for name in wanted])]


def _attitudes(scene: Scene) -> np.ndarray:
    """A of every body at every frame, ground's I last: (F, nb + 1, 3, 3)."""
    ground = np.broadcast_to(np.eye(3), (len(scene.times), 1, 3, 3))
    return np.concatenate([scene.rotations(), ground], axis=1)


def _place(scene: Scene, a: np.ndarray, body: int, point) -> np.ndarray:
    """Global path (F, 3) of a point fixed in body `body` (GROUND_INDEX: a global point)."""
    point = np.asarray(point, float)
    if body == GROUND_INDEX:
        return np.broadcast_to(point, (len(scene.times), 3)).copy()
    return np.einsum("fij,j->fi", a[:, body], point) + scene.r[:, body]


def _turn(a: np.ndarray, body: int, vector) -> np.ndarray:
    """Global direction (F, 3) of a vector fixed in body `body`."""
    return np.einsum("fij,j->fi", a[:, body], np.asarray(vector, float))


def _velocity(scene: Scene, columns, body: int, at: np.ndarray) -> np.ndarray:
    """Velocity (F, 3) of body `body`'s material point at `at`: v + w x (at - r); ground 0."""
    if body == GROUND_INDEX:
        return np.zeros_like(at)
    v, w = columns[body]
    return v + np.cross(w, at - scene.r[:, body])


# ---------------------------------------------------------------------------------- joints
def _frames(ir, metadata: Mapping | None) -> dict[str, str]:
    """Joint -> the frame its reaction columns are in: the run's metadata, else the model."""
    given = (metadata or {}).get("reaction_frames")
    frames = {joint.name: joint.reaction_frame for joint in ir.joints}
    if isinstance(given, Mapping):
        frames |= {name: entry["frame"] for name, entry in given.items()
                   if name in frames and isinstance(entry, Mapping)
                   and isinstance(entry.get("frame"), str)}
    return frames


def joint_arrows(ir, scene: Scene, a, names, values, rows, metadata) -> list[Arrow]:
    """Reaction force and torque of every joint, and the motor part along its axis."""
    from casmech.runtime.reaction_frames import FRAMES

    frames = _frames(ir, metadata)
    motorised = {motor.name: motor.type.removeprefix("motor_") for motor in ir.motors}
    arrows = []
    for joint in ir.joints:
        given = _columns(names, values, rows, [f"{joint.name}.{c}" for c in
                                               ("fx", "fy", "fz", "tx", "ty", "tz")])
        if given is None or frames[joint.name] not in FRAMES:
            continue
        rotation = FRAMES[frames[joint.name]](joint, a)  # (F, 3, 3): global <- frame
        force = np.einsum("fij,fj->fi", rotation, given[:, :3])
        torque = np.einsum("fij,fj->fi", rotation, given[:, 3:])
        if joint.reaction_point is not None:  # the table's torque is about Q: back to P
            arm = _turn(a, joint.body_i, np.asarray(joint.point_i) - joint.reaction_point)
            torque = torque - np.cross(arm, force)
        origin = _place(scene, a, joint.body_i, joint.point_i)
        carrier = (joint.body_i, np.asarray(joint.point_i, float))
        arrows += [Arrow("force", joint.name, origin, force, carrier),
                   Arrow("torque", joint.name, origin, torque, carrier)]
        if "w@i" not in joint.geometry:
            continue
        axis = _turn(a, joint.body_i, joint.geometry["w@i"])
        for drive in sorted({*joint.drivers, *([motorised[joint.name]]
                                               if joint.name in motorised else [])}):
            kind, about = _motor(drive)
            vector = torque if about else force
            along = np.einsum("fi,fi->f", vector, axis)[:, None] * axis
            arrows.append(Arrow(kind, joint.name, origin, along, carrier))
    return arrows


def triads(ir) -> list[Triad]:
    """Each joint's frame (u, v, w fixed in body_i) at its point on body_i."""
    out = []
    for joint in ir.joints:
        g = joint.geometry
        if not all(f"{axis}@i" in g for axis in "uvw"):
            continue
        origin = g.get("P@i", joint.point_i)
        out.append(Triad(joint.name, joint.body_i, np.asarray(origin, float),
                         np.column_stack([g[f"{axis}@i"] for axis in "uvw"])))
    return out


# -------------------------------------------------------------------------------- contacts
def _contact_points(force, scene: Scene, a) -> tuple[list, np.ndarray]:
    """[(P (F, 3), gap (F,))] of a contact element's points, and the normal (F, 3)."""
    points, params = force.points, force.params
    if force.type == "sphere_sphere":
        c_i = _place(scene, a, force.body_i, points["center_i"])
        c_j = _place(scene, a, force.body_j, points["center_j"])
        apart = np.linalg.norm(c_j - c_i, axis=1, keepdims=True)
        normal = (c_j - c_i) / np.where(apart > 0, apart, 1.0)
        gap = apart[:, 0] - params["radius_i"] - params["radius_j"]
        return [(c_i + (params["radius_i"] + gap / 2)[:, None] * normal, gap)], normal
    at = _place(scene, a, force.body_i, points["plane_at"])
    normal = _turn(a, force.body_i, force.axes["normal"])
    radius = params.get("radius", 0.0)
    keys = {"sphere_plane": ["center"],
            "points_plane": sorted((k for k in points if k.startswith("point")),
                                   key=lambda k: int(k[5:])),
            "capsule_plane": sorted((k for k in points if k.startswith("end")),
                                    key=lambda k: int(k[3:]))}[force.type]
    found = []
    for key in keys:
        centre = _place(scene, a, force.body_j, points[key])
        gap = np.einsum("fi,fi->f", normal, centre - at) - radius
        found.append((centre - (radius + gap / 2)[:, None] * normal, gap))
    return found, normal


def contact_arrows(ir, scene: Scene, a, names, values, rows) -> list[Arrow]:
    velocity = _columns(names, values, rows, [f"{b}.{c}" for b in scene.bodies
                                              for c in ("vx", "vy", "vz", "wx", "wy", "wz")])
    rates = None if velocity is None else {
        k: (velocity[:, 6 * k:6 * k + 3], velocity[:, 6 * k + 3:6 * k + 6])
        for k in range(len(scene.bodies))}
    arrows = []
    for force in ir.forces:
        if force.type not in CONTACTS:
            continue
        given = _columns(names, values, rows, [f"{force.name}.normal_force",
                                               f"{force.name}.friction_force"])
        if given is None:
            continue
        found, normal = _contact_points(force, scene, a)
        gaps = np.stack([gap for _, gap in found], axis=1)  # (F, points)
        weight = np.fmax(0.0, -gaps) ** force.params.get("exponent", 1.0)
        deepest = np.argmin(gaps, axis=1)
        total = weight.sum(axis=1, keepdims=True)
        share = np.where(total > 0, weight / np.where(total > 0, total, 1.0),
                         np.eye(len(found))[deepest])
        at = np.einsum("fk,kfi->fi", share, np.stack([p for p, _ in found]))
        arrows.append(Arrow("normal", force.name, at, given[:, :1] * normal))
        if rates is not None:
            slip = _velocity(scene, rates, force.body_j, at) - \
                _velocity(scene, rates, force.body_i, at)
            slip = slip - np.einsum("fi,fi->f", slip, normal)[:, None] * normal
            speed = np.linalg.norm(slip, axis=1, keepdims=True)
            direction = -slip / np.where(speed > 0, speed, 1.0)
            arrows.append(Arrow("friction", force.name, at, given[:, 1:] * direction))
    return arrows


def capsule(radius: float, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A capsule around the segment a-b: a UV sphere cut at its equator, the halves moved to
    the two ends (the band between them is the cylinder), turned from z onto b - a."""
    points, triangles = sphere(radius)
    axis = np.asarray(b, float) - np.asarray(a, float)
    length = float(np.linalg.norm(axis))
    points = points + np.where(points[:, 2:] >= 0, 0.5, -0.5) * [0, 0, length]
    w = axis / length
    u = np.cross(w, [1.0, 0, 0] if abs(w[0]) < 0.9 else [0, 1.0, 0])
    u /= np.linalg.norm(u)
    turn = np.column_stack([u, np.cross(w, u), w])
    return points @ turn.T + (np.asarray(a, float) + np.asarray(b, float)) / 2, triangles


def shapes(ir, size: float) -> list[Part]:
    """The spheres, capsules and points of the contact elements, in their bodies' frames."""
    out = []
    for force in ir.forces:
        if force.type not in CONTACTS:
            continue
        points, params, name = force.points, force.params, f"contact {force.name}"
        found = []
        if force.type == "sphere_plane":
            found.append((force.body_j, *sphere(params["radius"]), points["center"]))
        elif force.type == "sphere_sphere":
            found += [(force.body_i, *sphere(params["radius_i"]), points["center_i"]),
                      (force.body_j, *sphere(params["radius_j"]), points["center_j"])]
        elif force.type == "capsule_plane":
            found.append((force.body_j, *capsule(params["radius"], points["end0"],
                                                points["end1"]), np.zeros(3)))
        else:
            marker = sphere(0.5 * MARKER * size)
            found += [(force.body_j, *marker, points[key]) for key in points
                      if key.startswith("point")]
        out += [Part(name, body, -1, shape + np.asarray(at, float), triangles)
                for body, shape, triangles, at in found]
    return out


def planes(ir) -> list[Plane]:
    return [Plane(force.name, force.body_i, np.asarray(force.points["plane_at"], float),
                  np.asarray(force.axes["normal"], float))
            for force in ir.forces if force.type in CONTACTS and "plane_at" in force.points]


# ---------------------------------------------------------------------------------- extent
def extent(scene: Scene, a) -> tuple[np.ndarray, np.ndarray]:
    """Per frame: a sphere holding every part, centre (F, 3) and radius (F,): the centre of the
    smallest box holding the parts' convex hulls, the radius its largest distance to them."""
    paths = [scene.place(part.body, _hull(part.points), a) for part in scene.parts]
    if not paths:
        paths = [scene.r]
    low = np.min([path.min(axis=1) for path in paths], axis=0)
    high = np.max([path.max(axis=1) for path in paths], axis=0)
    centres = (low + high) / 2
    radius = np.max([np.linalg.norm(path - centres[:, None], axis=2).max(axis=1)
                     for path in paths], axis=0)
    return centres, np.where(radius > 0, radius, 1.0)


def _hull(points: np.ndarray) -> np.ndarray:
    """The vertices of a point cloud's convex hull (all points when it is flat or tiny): the
    lowest point along any direction is among them."""
    from scipy.spatial import ConvexHull, QhullError

    if len(points) < 5:
        return points
    try:
        return points[ConvexHull(points).vertices]
    except (QhullError, ValueError):
        return points


def ground(scene: Scene, ir, a) -> tuple[np.ndarray, np.ndarray]:
    """(point, normal): a contact plane on ground facing up, else the plane normal to up
    through the lowest point any part reaches over the frames."""
    for plane in planes(ir):
        if plane.body == GROUND_INDEX and float(plane.normal @ scene.up) > LEVEL:
            return plane.point, scene.up
    lowest, where = np.inf, np.zeros(3)
    for part in scene.parts:
        hull = _hull(part.points)
        path = scene.place(part.body, hull, a)
        heights = path @ scene.up
        k = np.unravel_index(np.argmin(heights), heights.shape)
        if heights[k] < lowest:
            lowest, where = float(heights[k]), path[k]
    return where, scene.up


# ---------------------------------------------------------------------------------- trails
def parse_trail(text: str, model: ResolvedModel) -> tuple[str, np.ndarray | None]:
    """`BODY` (its CM) or `BODY@X,Y,Z` (a point global at t = 0) -> (body, point or None)."""
    body, _, point = text.partition("@")
    bodies = [b.name for b in model.bodies]
    if body not in bodies:
        from difflib import get_close_matches

        close = get_close_matches(body, bodies, n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else f" (bodies: {', '.join(bodies)})"
        raise UsageError(f"--trail {text}: no body '{body}' in the model{hint}")
    if not point:
        return body, None
    try:
        numbers = np.array([float(x) for x in point.split(",")])
    except ValueError:
        numbers = np.array([])
    if numbers.shape != (3,) or not np.all(np.isfinite(numbers)):
        raise UsageError(f"--trail {text}: expected BODY or BODY@X,Y,Z with three numbers "
                         "(a point global at t = 0, like a joint's `at`)")
    return body, numbers


def trails(model: ResolvedModel, scene: Scene, a, chosen: Sequence[str]) -> list[Trail]:
    index = {b.name: k for k, b in enumerate(model.bodies)}
    if not chosen:
        return [Trail(name, k, scene.r[:, k].copy(), False)
                for k, name in enumerate(scene.bodies)]
    out = []
    for text in chosen:
        body, point = parse_trail(text, model)
        k = index[body]
        if point is None:
            out.append(Trail(body, k, scene.r[:, k].copy(), True))
            continue
        b = model.bodies[k]
        from casmech.io.animate import rotations

        local = rotations(b.euler_parameters).T @ (point - b.position)
        out.append(Trail(text, k, _place(scene, a, k, local), True))
    return out


# ---------------------------------------------------------------------------------- all
def build_overlays(model: ResolvedModel, scene: Scene, names: Sequence[str], values: np.ndarray,
                   rows: np.ndarray, metadata: Mapping | None = None,
                   chosen_trails: Sequence[str] = ()) -> Overlays:
    """The overlays of a scene built from the same table (`rows`: the rows it draws)."""
    from casmech.model.lower import lower

    ir = lower(model)
    a = _attitudes(scene)
    values = np.asarray(values, float)
    arrows = joint_arrows(ir, scene, a, names, values, rows, metadata)
    arrows += contact_arrows(ir, scene, a, names, values, rows)
    centres, radii = extent(scene, a)
    return Overlays(tuple(shapes(ir, 2 * float(np.median(radii)))), tuple(arrows),
                    tuple(triads(ir)), tuple(planes(ir)),
                    tuple(trails(model, scene, a, chosen_trails)),
                    ground(scene, ir, a), centres, radii)
