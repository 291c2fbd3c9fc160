"""The initial state of an MJCF model: joint values (qpos, qvel), then every body's pose and
velocity by MuJoCo's forward kinematics.

qpos0 (the pose written in the file) is each hinge's and slide's `ref`, a ball's identity
quaternion and a free body's pose in the file. A `<key>` of `<keyframe>` (`--keyframe NAME`)
gives qpos, qvel and ctrl (in MuJoCo's order of joints and actuators); `--position` and
`--velocity` then set single hinges and slides (radians or metres, as qpos). A body's frame
is its parent's times its own offset, then each of its joints in order: a hinge turns it by
(q - ref) about the joint's axis through the joint's point, a slide moves it by (q - ref)
along the axis, a ball turns it by the quaternion about its point, a free joint sets it. The
velocities follow: a ball's qvel and a free joint's angular velocity are in the body's own
frame, a free joint's linear velocity is the body origin's, global (MuJoCo's conventions).
"""

from __future__ import annotations

import numpy as np

from casmech.core.records import record
from casmech.errors import UsageError, did_you_mean
from casmech.importers.mjcf_bodies import QPOS, QVEL, Body, Joint, Tree
from casmech.importers.mjcf_frames import Frame, quaternion_matrix
from casmech.importers.mjcf_read import Element, Reader
from casmech.importers.urdf_tree import axis_rotation


@record(frozen=False)
class State:
    frames: dict[Body, Frame]  # global
    omega: dict[Body, np.ndarray]  # global
    velocity: dict[Body, np.ndarray]  # of the body frame's origin, global
    qpos: dict[Joint, np.ndarray]
    ctrl: np.ndarray | None  # a keyframe's ctrl
    axes: dict[Joint, tuple[np.ndarray, np.ndarray]] = None  # (axis, point), global


def qpos0(joint: Joint, world: Frame) -> np.ndarray:
    if joint.kind == "free":
        from casmech.core.quaternions import from_matrix

        return np.concatenate([world.origin, from_matrix(world.rotation)])
    if joint.kind == "ball":
        return np.array([1.0, 0.0, 0.0, 0.0])
    return np.array([joint.ref])


def keyframe(reader: Reader, tree: Tree, name: str) -> tuple[Element, dict[str, str]]:
    keys = [key for element in reader.root.findall("keyframe")
            for key in element.findall("key")]
    named = {key.attrib.get("name", str(k)): key for k, key in enumerate(keys)}
    if name in named:
        return named[name], named[name].attrib
    if name.isdigit() and int(name) < len(keys):
        return keys[int(name)], keys[int(name)].attrib
    raise UsageError(f"--keyframe {name}: no such <key>; "
                     + (did_you_mean(name, named) or "keys: " + (", ".join(named) or "none")))


def _key_values(reader: Reader, key: Element, attrib: dict, field: str, size: int
                ) -> np.ndarray | None:
    values = reader.numbers(key, attrib, field, "keyframe", (size,))
    return values


def initial_state(reader: Reader, tree: Tree, key_name: str | None,
                  positions: dict[str, float], velocities: dict[str, float],
                  actuators: int) -> State:
    nq = sum(QPOS[j.kind] for j in tree.joints)
    nv = sum(QVEL[j.kind] for j in tree.joints)
    qpos_all = qvel_all = ctrl = None
    if key_name is not None:
        key, attrib = keyframe(reader, tree, key_name)
        qpos_all = _key_values(reader, key, attrib, "qpos", nq)
        qvel_all = _key_values(reader, key, attrib, "qvel", nv)
        ctrl = _key_values(reader, key, attrib, "ctrl", actuators) if actuators else None
    by_name = {j.name: j for j in tree.joints}
    for values, what in ((positions, "position"), (velocities, "velocity")):
        for name, value in values.items():
            joint = by_name.get(name)
            if joint is None or joint.kind not in ("hinge", "slide"):
                options = [j.name for j in tree.joints if j.kind in ("hinge", "slide")]
                raise UsageError(f"initial joint {what}: '{name}' is not a hinge or slide joint "
                                 "of the model; " + (did_you_mean(name, options) or
                                                     "joints: " + ", ".join(options)))
            if not np.isfinite(value):
                raise UsageError(f"initial joint {what} of '{name}' is not a finite number")
    return _forward(tree, qpos_all, qvel_all, positions, velocities, ctrl)


def _forward(tree: Tree, qpos_all, qvel_all, positions, velocities, ctrl) -> State:
    state = State({tree.world: Frame(np.eye(3), np.zeros(3))}, {tree.world: np.zeros(3)},
                  {tree.world: np.zeros(3)}, {}, ctrl, {})
    iq = iv = 0
    for body in tree.bodies[1:]:
        parent = state.frames[body.parent]
        at = parent * body.local
        omega = state.omega[body.parent].copy()
        velocity = state.velocity[body.parent] + np.cross(omega, at.origin - parent.origin)
        for joint in body.joints:
            nq, nv = QPOS[joint.kind], QVEL[joint.kind]
            q = qpos_all[iq:iq + nq] if qpos_all is not None else qpos0(joint, at)
            dq = qvel_all[iv:iv + nv] if qvel_all is not None else np.zeros(nv)
            if joint.name in positions:
                q = np.array([positions[joint.name]])
            if joint.name in velocities:
                dq = np.array([velocities[joint.name]])
            iq, iv = iq + nq, iv + nv
            state.qpos[joint] = np.asarray(q, float)
            state.axes[joint] = (at.rotation @ joint.axis, at.point(joint.pos))
            at, omega, velocity = _move(joint, at, omega, velocity, q, dq)
        state.frames[body], state.omega[body], state.velocity[body] = at, omega, velocity
    return state


def _move(joint: Joint, at: Frame, omega, velocity, q, dq):
    """The body frame and its velocity after one joint (q: its qpos, dq: its qvel)."""
    anchor = at.point(joint.pos)
    axis = at.rotation @ joint.axis
    if joint.kind == "free":
        rotation = quaternion_matrix(q[3:7])
        return Frame(rotation, np.array(q[:3], float)), rotation @ dq[3:6], np.array(dq[:3])
    if joint.kind == "slide":
        moved = Frame(at.rotation, at.origin + (q[0] - joint.ref) * axis)
        carried = velocity + np.cross(omega, moved.origin - at.origin)
        return moved, omega, carried + dq[0] * axis
    if joint.kind == "hinge":
        turn = axis_rotation(axis, q[0] - joint.ref)
        rate = dq[0] * axis
    else:  # ball: q is the rotation in the body's frame, dq the angular velocity in the
        turn = at.rotation @ quaternion_matrix(q) @ at.rotation.T  # body's turned frame
        rate = turn @ at.rotation @ dq
    moved = Frame(turn @ at.rotation, anchor + turn @ (at.origin - anchor))
    velocity = velocity + np.cross(omega, moved.origin - at.origin) \
        + np.cross(rate, moved.origin - anchor)
    return moved, omega + rate, velocity


__all__ = ["State", "initial_state"]
