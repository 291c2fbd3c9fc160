"""A sequence of elementary joints between two bodies -> the casmech joint it amounts to.

URDF chains whose intermediate links have no mass, and MJCF bodies with several joints, join
two bodies by a sequence of hinges, slides and balls. When nothing carries mass between them,
the sequence constrains only the relative motion of the two bodies, which is one casmech joint
(or a few basic constraints) whenever the sequence spans a motion casmech has:

| sequence (any order where it does not matter) | casmech |
|---|---|
| hinge | `revolute` |
| slide | `translational` |
| ball | `spherical` |
| two hinges whose axes meet at right angles | `universal` (axis_i the first, axis_j the second) |
| three hinges whose axes meet in a point, not coplanar | `spherical` |
| hinge and slide along the same line | `cylindrical` |
| two slides and a hinge normal to both | `planar` |
| two or three independent slides | basic constraints (`basic_rows`) |

Slides only are three `dp1` rows (no relative rotation) and, for two slides, a `dp2` (no motion
along the plane's normal). The same configuration space, so the same motion of the two bodies
(dynamics included: the intermediate frames carry no mass). The first joint's axis is fixed in
the parent, the last one's in the child, as a universal joint's axes are. What does not
transfer is written by the callers: per-joint springs and dampers (their coordinates are gone)
and joint limits. Vectors are global, at the initial pose.
"""

from __future__ import annotations

import numpy as np

from casmech.core.records import record
from casmech.elements.joint_types import PERPENDICULAR
from casmech.importers.adm_frames import tidy

SAME = 1e-9  # relative distance below which two joint lines meet, two points coincide
INDEPENDENT = 1e-6  # |det| (or the smallest singular value) of unit axes above which they span


@record(eq=False)
class Elementary:
    kind: str  # "hinge" | "slide" | "ball"
    axis: np.ndarray  # unit, global (not used for a ball)
    point: np.ndarray  # a point of the joint's line (its anchor), global
    name: str = ""


@record(eq=False)
class BodyFrame:
    """A body's rotation (columns: its axes, global) and origin (global), for basic
    constraints written in body frames."""

    rotation: np.ndarray
    origin: np.ndarray


def meeting_point(hinges: list[Elementary], scale: float) -> np.ndarray | None:
    """The point where every hinge's line passes (least squares), None when they miss it."""
    lhs, rhs = np.zeros((3, 3)), np.zeros(3)
    for hinge in hinges:
        projector = np.eye(3) - np.outer(hinge.axis, hinge.axis)
        lhs += projector
        rhs += projector @ hinge.point
    if np.linalg.svd(lhs, compute_uv=False)[-1] < INDEPENDENT:
        return None  # parallel lines: no single point
    point = np.linalg.solve(lhs, rhs)
    for hinge in hinges:
        off = (np.eye(3) - np.outer(hinge.axis, hinge.axis)) @ (point - hinge.point)
        if np.linalg.norm(off) > SAME * scale:
            return None
    return point


def _spans(axes: list[np.ndarray]) -> bool:
    return np.linalg.svd(np.array(axes), compute_uv=False)[-1] > INDEPENDENT


def _parallel(a: np.ndarray, b: np.ndarray) -> bool:
    return np.linalg.norm(np.cross(a, b)) < PERPENDICULAR


def compose(chain: list[Elementary], scale: float = 1.0) -> dict | None:
    """{"type": casmech type, keys...} of a sequence of joints, {"type": "basic", "slides":
    axes} for slides only (see `basic_rows`), or None when casmech has no such joint."""
    hinges = [j for j in chain if j.kind == "hinge"]
    slides = [j for j in chain if j.kind == "slide"]
    balls = [j for j in chain if j.kind == "ball"]
    scale = max(1.0, scale)
    if balls:
        return {"type": "spherical", "at": tidy(balls[0].point)} if len(chain) == 1 else None
    if not slides:
        if len(hinges) == 1:
            return {"type": "revolute", "at": tidy(hinges[0].point), "axis": tidy(hinges[0].axis)}
        point = meeting_point(hinges, scale)
        if point is None:
            return None
        if len(hinges) == 2 and abs(hinges[0].axis @ hinges[1].axis) < PERPENDICULAR:
            return {"type": "universal", "at": tidy(point, scale), "axis_i": tidy(hinges[0].axis),
                    "axis_j": tidy(hinges[1].axis)}
        if len(hinges) == 3 and _spans([h.axis for h in hinges]):
            return {"type": "spherical", "at": tidy(point, scale)}
        return None
    if not hinges:
        if len(slides) == 1:
            return {"type": "translational", "at": tidy(slides[0].point),
                    "axis": tidy(slides[0].axis)}
        if len(slides) <= 3 and _spans([s.axis for s in slides]):
            return {"type": "basic", "slides": [s.axis for s in slides],
                    "point": slides[0].point}
        return None
    if len(hinges) == 1 and len(slides) == 1 and _parallel(hinges[0].axis, slides[0].axis):
        return {"type": "cylindrical", "at": tidy(hinges[0].point), "axis": tidy(hinges[0].axis)}
    if len(hinges) == 1 and len(slides) == 2 and _spans([s.axis for s in slides]):
        normal = np.cross(slides[0].axis, slides[1].axis)
        normal /= np.linalg.norm(normal)
        if _parallel(hinges[0].axis, normal):
            return {"type": "planar", "at": tidy(hinges[0].point), "axis": tidy(hinges[0].axis)}
    return None


def basic_rows(composed: dict, frame_i: BodyFrame, frame_j: BodyFrame) -> list[dict]:
    """The basic constraints of slides only: no relative rotation (three dp1 rows between
    global directions perpendicular at the initial pose, in each body's frame) and, for two
    slides, no motion of body_j's copy of the anchor along the plane's normal (a dp2)."""
    local_i = frame_i.rotation.T
    local_j = frame_j.rotation.T
    rows = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        rows.append({"type": "dp1", "a_i": tidy(local_i[:, a]), "a_j": tidy(local_j[:, b])})
    slides = composed["slides"]
    if len(slides) == 2:
        normal = np.cross(slides[0], slides[1])
        normal /= np.linalg.norm(normal)
        point = composed["point"]
        rows.append({"type": "dp2", "a_i": tidy(local_i @ normal),
                     "s_i": tidy(local_i @ (point - frame_i.origin)),
                     "s_j": tidy(local_j @ (point - frame_j.origin))})
    return rows


def name_of(names: list[str], fallback: str) -> str:
    """A composite joint's name: the common prefix of its joints' names (`hip_x`, `hip_y` ->
    `hip`) when it is a word of 3 characters or more, else `fallback`."""
    if len(names) == 1:
        return names[0]
    prefix = names[0]
    for name in names[1:]:
        while not name.startswith(prefix):
            prefix = prefix[:-1]
    prefix = prefix.rstrip("_-. ")
    return prefix if len(prefix) >= 3 else fallback
