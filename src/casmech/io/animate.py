"""What `casmech animate` draws: body shapes in body frames, joint markers, and the poses per frame.

A Scene is independent of any file format: vtk.py writes it as a ParaView time series, and
html_player.py as a self-contained browser player. Every part is a triangle surface fixed in one
body's frame (ground: the global frame); its global points at a frame are r + A(p) x_bar with r, p
read from results.csv (p normalised first, so a slightly drifted row still draws a rigid body).

Shapes come from each body's `geometry` (box, cylinder, sphere, STL or any meshio surface mesh,
Collada .dae through pycollada; each item placed in the body frame by its `offset` and
`orientation`). A body without geometry is drawn as its equivalent inertia ellipsoid: the
uniform solid ellipsoid with the body's mass and inertia, I_x = m (b^2 + c^2) / 5 etc.,
along the principal axes of inertia.
"""

from __future__ import annotations

import warnings
from functools import cache
from pathlib import Path

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.core.records import record
from casmech.errors import Diagnostic, ModelError, UsageError
from casmech.schema.loader import load_document
from casmech.schema.resolved import GROUND, ResolvedModel

GROUND_INDEX = -1
SEGMENTS = 24  # around a cylinder or a sphere's equator
RINGS = 12  # pole to pole on a sphere
MARKER = 0.015  # joint marker radius as a fraction of the scene's size
THINNEST = 0.05  # smallest ellipsoid semi-axis, as a fraction of the largest
POSE = ("x", "y", "z", "e0", "e1", "e2", "e3")


@record
class Part:
    """A triangle surface fixed in the frame of body `body` (GROUND_INDEX: global)."""

    name: str  # body name, or "joint <name>"
    body: int
    joint: int  # index of the joint a marker belongs to; -1 for body geometry
    points: np.ndarray  # (n, 3) in the body frame
    triangles: np.ndarray  # (m, 3) indices into points


@record
class Link:
    """A line between a point of one body and a point of another (e.g. a distance joint)."""

    joint: int
    body_a: int
    point_a: np.ndarray
    body_b: int
    point_b: np.ndarray


@record
class Scene:
    name: str
    bodies: tuple[str, ...]
    joints: tuple[str, ...]
    parts: tuple[Part, ...]
    links: tuple[Link, ...]
    times: np.ndarray  # (F,)
    r: np.ndarray  # (F, nb, 3) CM positions
    p: np.ndarray  # (F, nb, 4) unit Euler parameters
    up: np.ndarray  # (3,) unit: against gravity (z when there is none)
    rows: np.ndarray | None = None  # the results rows drawn, one per frame

    def rotations(self) -> np.ndarray:
        """A(p) of every body at every frame, (F, nb, 3, 3)."""
        return rotations(self.p)

    def place(self, body: int, points: np.ndarray, rotations: np.ndarray,
              frames=slice(None)) -> np.ndarray:
        """Global points (F, n, 3) of body-frame points at the given frames (default: all);
        `rotations` is self.rotations()."""
        if body == GROUND_INDEX:
            return np.broadcast_to(points, (len(self.times[frames]), *points.shape))
        moved = np.einsum("fij,nj->fni", rotations[frames, body], points)
        return moved + self.r[frames, body, None, :]


# ---------------------------------------------------------------------------------- shapes
def box(size) -> tuple[np.ndarray, np.ndarray]:
    """8 corners of a box centred at the origin, 12 outward triangles."""
    half = np.asarray(size, float) / 2
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    triangles = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]
    return corners * half, np.array(triangles)


def cylinder(radius: float, length: float, axis: str = "z") -> tuple[np.ndarray, np.ndarray]:
    """Closed cylinder centred at the origin along a body axis: two rims and two cap centres."""
    angle = np.linspace(0, 2 * np.pi, SEGMENTS, endpoint=False)
    rim = np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])
    ends = [np.column_stack([rim, np.full(SEGMENTS, h)]) for h in (-length / 2, length / 2)]
    points = np.vstack([*ends, [[0, 0, -length / 2], [0, 0, length / 2]]])
    k, n = np.arange(SEGMENTS), (np.arange(SEGMENTS) + 1) % SEGMENTS
    bottom, top = 2 * SEGMENTS, 2 * SEGMENTS + 1
    triangles = np.vstack([
        np.column_stack([k, n, n + SEGMENTS]), np.column_stack([k, n + SEGMENTS, k + SEGMENTS]),
        np.column_stack([np.full(SEGMENTS, bottom), n, k]),
        np.column_stack([np.full(SEGMENTS, top), k + SEGMENTS, n + SEGMENTS]),
    ])
    order = {"x": [2, 0, 1], "y": [1, 2, 0], "z": [0, 1, 2]}[axis]  # body axis <- local z
    return points[:, order], triangles


def sphere(radius: float) -> tuple[np.ndarray, np.ndarray]:
    """UV sphere: RINGS - 1 latitude rings of SEGMENTS points plus the two poles."""
    polar = np.linspace(0, np.pi, RINGS + 1)[1:-1]
    angle = np.linspace(0, 2 * np.pi, SEGMENTS, endpoint=False)
    ring = np.stack([np.outer(np.sin(polar), np.cos(angle)), np.outer(np.sin(polar), np.sin(angle)),
                     np.outer(np.cos(polar), np.ones(SEGMENTS))], axis=-1).reshape(-1, 3)
    points = np.vstack([ring, [[0, 0, 1], [0, 0, -1]]]) * radius
    north, south = len(ring), len(ring) + 1
    k, n = np.arange(SEGMENTS), (np.arange(SEGMENTS) + 1) % SEGMENTS
    bands = [np.column_stack([r * SEGMENTS + k, (r + 1) * SEGMENTS + k, (r + 1) * SEGMENTS + n])
             for r in range(RINGS - 2)]
    bands += [np.column_stack([r * SEGMENTS + k, (r + 1) * SEGMENTS + n, r * SEGMENTS + n])
              for r in range(RINGS - 2)]
    last = (RINGS - 2) * SEGMENTS
    caps = [np.column_stack([np.full(SEGMENTS, north), k, n]),
            np.column_stack([np.full(SEGMENTS, south), last + n, last + k])]
    return points, np.vstack(bands + caps)


def inertia_ellipsoid(mass: float, inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The uniform solid ellipsoid of this mass and inertia, on the principal axes."""
    moments, axes = np.linalg.eigh(np.asarray(inertia, float))
    squares = 2.5 / mass * (moments.sum() - 2 * moments)  # a^2 = 5 (Iy + Iz - Ix) / (2 m)
    semi = np.sqrt(np.clip(squares, 0, None))
    semi = np.maximum(semi, THINNEST * semi.max())
    points, triangles = sphere(1.0)
    return (points * semi) @ axes.T, triangles


def meshio_module():
    """meshio (a dependency of casmech, imported on use), or a usage error saying how to
    install it."""
    try:
        import meshio
    except ImportError:
        raise UsageError("VTK output and mesh geometry need meshio, a dependency of casmech "
                         "missing here; install it with: pip install meshio") from None
    return meshio


def collada_file(path: Path, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """A Collada (.dae) file read by pycollada: the triangles of every geometry its scene
    places, with the scene's node transforms and its `<unit meter>` applied (_unbound_primitives
    where pycollada binds none), then scaled. Its
    `up_axis` is not applied: the coordinates are taken as written, like the other formats."""
    try:
        import collada
    except ImportError:
        raise UsageError("Collada (.dae) meshes need pycollada, a dependency of casmech missing "
                         "here; install it with: pip install pycollada") from None
    with warnings.catch_warnings():  # pycollada's use of numpy.matrix
        warnings.simplefilter("ignore", PendingDeprecationWarning)
        try:
            document = collada.Collada(str(path), ignore=[collada.common.DaeUnsupportedError,
                                                          collada.common.DaeBrokenRefError])
            unit = float(getattr(document.assetInfo, "unitmeter", None) or 1.0)
            points, triangles, count = [], [], 0
            placed = list(document.scene.objects("geometry")) if document.scene else []
            primitives = ([p for g in placed for p in g.primitives()] if placed else
                          _unbound_primitives(document))
            for primitive in primitives:
                if isinstance(primitive, (collada.triangleset.BoundTriangleSet,
                                          collada.triangleset.TriangleSet)):
                    found = primitive
                elif isinstance(primitive, (collada.polylist.BoundPolylist,
                                            collada.polylist.Polylist)):  # polygons too
                    found = primitive.triangleset()
                else:
                    continue  # lines
                if found.vertex is None or not len(found.vertex_index):
                    continue
                points.append(np.asarray(found.vertex, float))
                triangles.append(np.asarray(found.vertex_index, int).reshape(-1, 3) + count)
                count += len(found.vertex)
        except collada.common.DaeError as error:
            raise ValueError(f"pycollada cannot read it: {error}") from None
    if not triangles:
        raise ValueError("no triangles in the Collada scene")
    return np.vstack(points) * unit * scale, np.vstack(triangles)


def _unbound_primitives(document) -> list:
    """The primitives a Collada scene places when pycollada bound none of its geometries (a
    broken material reference drops them): each node's `<instance_geometry>` read from its
    XML, the geometry's primitives bound to the product of the node transforms above it."""
    geometries = {geometry.id: geometry for geometry in document.geometries}
    found = []

    def walk(node, matrix):
        for child in node.xmlnode:
            if child.tag.endswith("instance_geometry"):
                geometry = geometries.get((child.get("url") or "").lstrip("#"))
                if geometry is not None:
                    found.extend(geometry.bind(matrix, {}).primitives())
        for child in node.children:
            if hasattr(child, "matrix") and hasattr(child, "xmlnode"):
                walk(child, matrix @ child.matrix)

    for node in document.scene.nodes if document.scene else ():
        walk(node, np.asarray(node.matrix, float))
    return found


def obj_geometry(path: Path, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """An OBJ file's vertices and faces alone (`v` and `f` lines; a face's polygon split into
    a fan of triangles, negative indices counted from the end), scaled: for the files whose
    texture coordinates or normals meshio cannot pair with the vertices."""
    points, triangles = [], []
    with path.open(encoding="utf-8", errors="replace") as lines:
        for line in lines:
            kind, _, rest = line.strip().partition(" ")
            if kind == "v":
                points.append([float(value) for value in rest.split()[:3]])
            elif kind == "f":
                corners = [int(item.split("/")[0]) for item in rest.split()]
                corners = [c - 1 if c > 0 else len(points) + c for c in corners]
                triangles += [[corners[0], corners[k], corners[k + 1]]
                              for k in range(1, len(corners) - 1)]
    if not triangles:
        raise ValueError("no faces in the OBJ file")
    faces = np.array(triangles, int)
    if faces.min() < 0 or faces.max() >= len(points):
        raise ValueError("a face names a vertex the OBJ file does not have")
    return np.array(points, float) * scale, faces


def mesh_file(path: Path, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """A surface mesh read by meshio (STL, OBJ, PLY, ...; Collada .dae by collada_file): its
    triangles (quads split), scaled."""
    if path.suffix.lower() == ".dae":
        return collada_file(path, scale)
    meshio = meshio_module()
    with warnings.catch_warnings():  # meshio's binary-STL size probe overflows on ASCII files
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            mesh = meshio.read(path)
        except meshio.ReadError as error:
            raise ValueError(str(error) or "meshio cannot read it") from None
        except ValueError:  # an OBJ whose texture or normal lists meshio cannot pair
            if path.suffix.lower() != ".obj":
                raise
            return obj_geometry(path, scale)
    triangles = [block.data for block in mesh.cells if block.type == "triangle"]
    triangles += [block.data[:, corners] for block in mesh.cells if block.type == "quad"
                  for corners in ([0, 1, 2], [0, 2, 3])]
    if not triangles:
        raise ValueError("no triangles or quads in the mesh")
    return np.asarray(mesh.points[:, :3], float) * scale, np.vstack(triangles)


SHAPES = {
    "box": lambda item, folder: box(item["size"]),
    "cylinder": lambda item, folder: cylinder(item["radius"], item["length"], item["axis"]),
    "sphere": lambda item, folder: sphere(item["radius"]),
    "mesh": lambda item, folder: mesh_file(folder / item["file"], item["scale"]),
}


# ---------------------------------------------------------------------------------- poses
@cache
def rotation_function() -> ca.Function:
    """p -> vec(A(p)), built on first use (nothing is built at import)."""
    p = ca.SX.sym("p", 4)
    return ca.Function("A", [p], [ca.vec(euler.rotation(p))], ["p"], ["A"])


def rotations(p: np.ndarray) -> np.ndarray:
    """A(p) (core/euler.py's) for an array (..., 4) of unit Euler parameters -> (..., 3, 3)."""
    flat = np.asarray(p, float).reshape(-1, 4)
    if not len(flat):
        return np.zeros((*p.shape[:-1], 3, 3))
    columns = np.asarray(rotation_function().map(len(flat))(flat.T))  # (9, n), column-major A
    return columns.T.reshape(-1, 3, 3).transpose(0, 2, 1).reshape(*p.shape[:-1], 3, 3)


def body_poses(names: list[str], values: np.ndarray, bodies: tuple[str, ...]):
    """t, r (F, nb, 3) and unit p (F, nb, 4) from a results table."""
    column = {name: k for k, name in enumerate(names)}
    wanted = ["t"] + [f"{body}.{c}" for body in bodies for c in POSE]
    missing = [name for name in wanted if name not in column]
    if missing:
        shown = ", ".join(missing[:4]) + (", ..." if len(missing) > 4 else "")
        raise UsageError(f"the results have no column {shown}; expected t and x, y, z, e0..e3 of "
                         f"every body of the model (hint: animate results.csv written by "
                         f"`casmech run` from this model)")
    if not len(values):
        raise UsageError("the results have no rows to animate")
    if np.any(np.diff(values[:, column["t"]]) < 0):
        raise UsageError("the results' t column decreases somewhere; expected one run's rows in "
                         "time order")
    pose = values[:, [column[name] for name in wanted[1:]]].reshape(len(values), len(bodies), 7)
    p = pose[..., 3:]
    norm = np.linalg.norm(p, axis=-1, keepdims=True)
    if not np.all(np.isfinite(pose)) or np.any(norm < 0.5):
        raise UsageError("the results hold non-finite positions or Euler parameters far from unit "
                         "norm; they cannot be drawn")
    return values[:, column["t"]], pose[..., :3], p / norm


def select_rows(times: np.ndarray, every: int | None = None, fps: float | None = None):
    """Indices of the rows to draw: all, every K-th (last kept), or the nearest to k / fps."""
    if every is not None and fps is not None:
        raise UsageError("give --every or --fps, not both")
    if every is not None:
        if every < 1:
            raise UsageError(f"--every must be a positive integer (got {every})")
        rows = np.arange(0, len(times), every)
        return np.union1d(rows, [len(times) - 1])
    if fps is not None:
        if not fps > 0:
            raise UsageError(f"--fps must be positive (got {fps})")
        wanted = np.arange(times[0], times[-1] + 0.5 / fps, 1.0 / fps)
        rows = np.clip(np.searchsorted(times, wanted), 1, len(times) - 1)
        nearer = np.where(wanted - times[rows - 1] <= times[rows] - wanted, rows - 1, rows)
        return np.unique(nearer if len(times) > 1 else [0])
    return np.arange(len(times))


# ---------------------------------------------------------------------------------- scene
def body_parts(model: ResolvedModel) -> list[Part]:
    folder = Path(model.file).parent
    parts, problems = [], []
    for index, body in enumerate(model.bodies):
        if not body.geometry:
            points, triangles = inertia_ellipsoid(body.mass, body.inertia)
            parts.append(Part(body.name, index, -1, points, triangles))
        for n, item in enumerate(body.geometry):
            try:
                points, triangles = SHAPES[item["type"]](item, folder)
            except (OSError, ValueError) as error:
                problems.append(mesh_problem(model, index, n, item, error))
                continue
            placed = points @ rotations(item["euler_parameters"]).T + item["offset"]
            parts.append(Part(body.name, index, -1, placed, np.asarray(triangles, int)))
    if problems:
        raise ModelError(problems)
    return parts


def mesh_problem(model: ResolvedModel, body: int, item: int, given, error) -> Diagnostic:
    path = ("bodies", body, "geometry", item, "mesh")
    try:
        source = load_document(model.text, model.file).locate(path)
    except Exception:  # noqa: BLE001 - the location is a courtesy; the message stands alone
        source = model.bodies[body].source
    reason = getattr(error, "strerror", None) or str(error) or type(error).__name__
    return Diagnostic("E410", f"bodies[{body}].geometry[{item}].mesh",
                      f"cannot read mesh '{given['file']}': {reason}", source,
                      expected="a surface mesh file: STL, OBJ, PLY (meshio) or Collada .dae, "
                               "relative to the model file",
                      hint=f"looked in {Path(model.file).parent.resolve()}")


def joint_points(model: ResolvedModel) -> list[tuple[int, tuple]]:
    """(joint index, ((body, body-frame point), ...)) for every joint that has points."""
    index = {b.name: k for k, b in enumerate(model.bodies)} | {GROUND: GROUND_INDEX}
    frames = {b.name: (b.position, rotations(b.euler_parameters)) for b in model.bodies}
    frames[GROUND] = (np.zeros(3), np.eye(3))

    def local(body: str, point) -> tuple[int, np.ndarray]:
        r0, a0 = frames[body]
        return index[body], a0.T @ (np.asarray(point, float) - r0)

    result = []
    for k, joint in enumerate(model.joints):
        v = joint.vectors
        if "s_i" in v or "s_j" in v:  # basic constraints: body-frame points as written
            ends = [(index[b], np.asarray(v[s], float)) for b, s in
                    ((joint.body_i, "s_i"), (joint.body_j, "s_j")) if s in v]
        elif "at_i" in v:  # distance
            ends = [local(joint.body_i, v["at_i"]), local(joint.body_j, v["at_j"])]
        elif "at" in v:
            ends = [local(joint.body_i, v["at"]),
                    local(joint.body_j, v.get("at_j", v["at"]))]
        else:
            ends = []
        if ends:
            result.append((k, tuple(ends)))
    return result


def scene_size(model: ResolvedModel, parts: list[Part]) -> float:
    """Diagonal of the initial configuration's bounding box (1 when it is a point)."""
    frames = {k: (b.position, rotations(b.euler_parameters)) for k, b in enumerate(model.bodies)}
    frames[GROUND_INDEX] = (np.zeros(3), np.eye(3))
    points = [part.points @ frames[part.body][1].T + frames[part.body][0] for part in parts]
    points.append(np.array([b.position for b in model.bodies]).reshape(-1, 3))
    cloud = np.vstack(points)
    size = float(np.linalg.norm(cloud.max(axis=0) - cloud.min(axis=0)))
    return size if size > 0 else 1.0


def build_scene(model: ResolvedModel, names: list[str], values: np.ndarray,
                every: int | None = None, fps: float | None = None) -> Scene:
    bodies = tuple(b.name for b in model.bodies)
    times, r, p = body_poses(names, values, bodies)
    rows = select_rows(times, every, fps)
    parts = body_parts(model)
    size = scene_size(model, parts)
    marker, triangles = sphere(MARKER * size)
    links = []
    for joint, ends in joint_points(model):
        name = f"joint {model.joints[joint].name}"
        for body, point in ends:
            parts.append(Part(name, body, joint, marker + point, triangles))
        if len(ends) == 2 and _apart(model, *ends) > 1e-9 * size:  # not one point seen twice
            links.append(Link(joint, ends[0][0], ends[0][1], ends[1][0], ends[1][1]))
    gravity = np.asarray(model.gravity, float)
    up = -gravity / np.linalg.norm(gravity) if np.linalg.norm(gravity) else np.array([0, 0, 1.0])
    return Scene(model.name, bodies, tuple(j.name for j in model.joints), tuple(parts),
                 tuple(links), times[rows], r[rows], p[rows], up, rows)


def _apart(model: ResolvedModel, *ends: tuple[int, np.ndarray]) -> float:
    """Distance at t = 0 (the file's pose) between body-frame points of two bodies."""
    def initial(body: int, point: np.ndarray) -> np.ndarray:
        if body == GROUND_INDEX:
            return point
        b = model.bodies[body]
        return b.position + rotations(b.euler_parameters) @ point

    return float(np.linalg.norm(initial(*ends[0]) - initial(*ends[1])))
