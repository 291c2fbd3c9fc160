"""The frame and point of each joint's reaction columns (docs/format.md, `reactions:`).

equations.eom.reactions gives every joint's reaction in global components: the force on body_j
and the torque about body_i's joint point. A joint whose frame is not `global` has both vectors
written along that frame's axes instead, at every row: v_frame = R^T v_global, where R (columns:
the frame's axes in global components) is

    global  I
    body_i  A_i, body i's orientation (ground: I)
    body_j  A_j
    joint   A_i U, U the joint frame's axes (u, v, w) in body i's frame: the triad the joint's
            constraints and joint coordinates use (model.lower.joint_frame: w the joint's
            `axis`, u and v perpendicular to it; a joint without `axis` has the global axes at
            the file's pose), carried by body i

A joint with `reactions: {point: Q}` (global at t = 0, carried by body i like the joint point
P) has its torque taken about Q instead, before the rotation: T_Q = T_P + (P - Q) x F, with
P - Q = A_i (s_P - s_Q) from the two points in body i's frame. All rows at once (einsum).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from casmech.errors import UsageError
from casmech.model.ir import GROUND_INDEX, JointIR, ModelIR

DEFAULT = "global"


def joint_axes(joint: JointIR) -> np.ndarray:
    """U: the joint frame's u, v, w as columns, in body i's frame (ground: global)."""
    return np.column_stack([joint.geometry[f"{axis}@i"] for axis in "uvw"])


# frame -> (joint, A (rows, n_bodies + 1, 3, 3): every body's A, ground's I last) -> R per row
FRAMES: dict[str, Callable[[JointIR, np.ndarray], np.ndarray]] = {
    "global": lambda joint, a: np.broadcast_to(np.eye(3), (len(a), 3, 3)),
    "body_i": lambda joint, a: a[:, joint.body_i],
    "body_j": lambda joint, a: a[:, joint.body_j],
    "joint": lambda joint, a: a[:, joint.body_i] @ joint_axes(joint),
}
assert GROUND_INDEX == -1  # FRAMES reads ground's I as the last "body"


def chosen(ir: ModelIR, override: str | Mapping[str, str] | None = None) -> dict[str, str]:
    """Joint name -> frame: the model's `reactions: {frame: ...}` (default global), replaced by
    `override` for every joint (a frame name) or for the joints it names (a mapping)."""
    frames = {joint.name: joint.reaction_frame for joint in ir.joints}
    given = dict.fromkeys(frames, override) if isinstance(override, str) else dict(override or {})
    unknown = sorted(set(given) - set(frames))
    if unknown:
        raise UsageError(f"reaction frames for {', '.join(unknown)}: no such joint in the model "
                         f"(joints: {', '.join(frames) or 'none'})")
    wrong = sorted({frame for frame in given.values() if frame not in FRAMES})
    if wrong:
        raise UsageError(f"reaction frame '{wrong[0]}' is not one of {', '.join(FRAMES)}")
    return frames | given


def body_rotations(p: np.ndarray) -> np.ndarray:
    """A(p / |p|) of every body at every row, then ground's I: p (rows, n_bodies, 4) ->
    (rows, n_bodies + 1, 3, 3)."""
    p = p / np.linalg.norm(p, axis=-1, keepdims=True)
    e0, e = p[..., 0, None, None], p[..., 1:]
    skew = np.zeros((*e.shape[:-1], 3, 3))
    skew[..., 0, 1], skew[..., 0, 2], skew[..., 1, 2] = -e[..., 2], e[..., 1], -e[..., 0]
    skew -= np.swapaxes(skew, -1, -2)
    a = ((2 * e0**2 - 1) * np.eye(3) + 2 * e[..., :, None] * e[..., None, :] + 2 * e0 * skew)
    ground = np.broadcast_to(np.eye(3), (len(p), 1, 3, 3))
    return np.concatenate([a, ground], axis=1)


def attitudes(ir: ModelIR, q: np.ndarray) -> np.ndarray:
    """body_rotations at every row of q (rows, 7 n_bodies, the r-p coordinates)."""
    nb = ir.n_bodies
    return body_rotations(q[:, 3 * nb:].reshape(len(q), nb, 4))


def orientations(ir: ModelIR, frames: Mapping[str, str], a: np.ndarray) -> np.ndarray:
    """R of every joint's reaction frame at every row (a: attitudes) -> (rows, n_joints, 3, 3)."""
    return np.stack([FRAMES[frames[joint.name]](joint, a) for joint in ir.joints], axis=1)


def moved(ir: ModelIR, a: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """Global reactions (rows, n_joints, 2, 3: force, torque) with each torque about its
    joint's reaction point (a: attitudes); unchanged when no joint names one."""
    joints = [k for k, joint in enumerate(ir.joints) if joint.reaction_point is not None]
    if not joints:
        return vectors
    vectors = vectors.copy()
    for k in joints:  # a loop over the joints that name a point, each over all rows
        joint = ir.joints[k]
        arm = a[:, joint.body_i] @ (np.asarray(joint.point_i) - joint.reaction_point)
        vectors[:, k, 1] += np.cross(arm, vectors[:, k, 0])
    return vectors


def rotate(ir: ModelIR, frames: Mapping[str, str], a: np.ndarray,
           vectors: np.ndarray) -> np.ndarray:
    """Global reactions (rows, n_joints, 2, 3) in each joint's frame (a: attitudes)."""
    if all(frames[joint.name] == DEFAULT for joint in ir.joints):
        return vectors
    return np.einsum("rjab,rjka->rjkb", orientations(ir, frames, a), vectors)


def written(ir: ModelIR, frames: Mapping[str, str], q: np.ndarray,
            reactions: np.ndarray) -> np.ndarray:
    """The table's reaction columns (rows, n_joints * 6: fx fy fz tx ty tz per joint, global)
    as it writes them: each torque moved to its point, then both vectors in the frame."""
    unchanged = all(frames[joint.name] == DEFAULT and joint.reaction_point is None
                    for joint in ir.joints)
    if unchanged:
        return reactions
    a = attitudes(ir, q)
    vectors = reactions.reshape(len(q), len(ir.joints), 2, 3)
    return rotate(ir, frames, a, moved(ir, a, vectors)).reshape(reactions.shape)


def describe(ir: ModelIR, frames: Mapping[str, str], body_names) -> dict[str, dict]:
    """For metadata.json: per joint, its reaction frame, the body that carries it and (joint
    frame) the axes u, v, w in that body's frame; a reaction point, in body i's frame."""
    def name(k: int) -> str:
        return "ground" if k == GROUND_INDEX else body_names[k]

    out = {}
    for joint in ir.joints:
        frame = frames[joint.name]
        entry: dict = {"frame": frame}
        if frame in ("body_i", "joint"):
            entry["body"] = name(joint.body_i)
        if frame == "body_j":
            entry["body"] = name(joint.body_j)
        if frame == "joint":
            entry["axes"] = {axis: joint.geometry[f"{axis}@i"].tolist() for axis in "uvw"}
        if joint.reaction_point is not None:
            entry["point"] = {"body": name(joint.body_i),
                              "position": np.asarray(joint.reaction_point).tolist()}
        out[joint.name] = entry
    return out
