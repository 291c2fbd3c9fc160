"""The recursions of the joint formulation over a spanning tree (compiler/tree.py), in SX and
O(N) in the number of bodies: forward kinematics, the articulated-body algorithm (Featherstone,
Rigid Body Dynamics Algorithms, 2008, table 7.1) and the backward Newton-Euler pass that gives
each tree joint's constraint wrench.

Spatial vectors are per body, in its frame at its CM, angular part first (compiler/spatial.py):
velocity V = (omega_bar, A^T r_dot), inertia [[J_bar, 0], [0, m 1]], force (n_bar, A^T F). A
tree joint's motion subspace S and the rate term c_J = S_dot u come from AD of its registry
entry (compiler/joint_motions.py). Applied forces are the r-p ones (eom.applied_forces: gravity,
force elements, effort motors) evaluated on the tree's poses and velocities, as body wrenches; a
driver's coordinate is a function of time (its rate and acceleration by AD).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import casadi as ca

from casmech.compiler import eom, euler, spatial
from casmech.compiler.assemble import GROUND_POSE, Coordinates
from casmech.compiler.ir import GROUND_INDEX, ModelIR
from casmech.compiler.joint_motions import MOTIONS, conjugate, from_matrix, product
from casmech.compiler.tree import TreeJoint


@cache
def local_motion(kind: str) -> ca.Function:
    """(theta, u) -> (rotation quaternion, translation, S_J, c_J, theta_dot) of a joint type:
    S_J maps u to the twist of F_c relative to F_p in F_c coordinates (angular first, the
    origin's velocity second), c_J = S_J_dot u."""
    motion = MOTIONS[kind]
    theta, u = ca.SX.sym("theta", motion.n_q), ca.SX.sym("u", motion.n_v)
    rotation, translation = motion.rotation(theta), motion.translation(theta)
    theta_dot = motion.rates(theta, u)
    omega = motion.angular_velocity(theta, u)
    if omega is None:
        omega = 2 * euler.g_matrix(rotation) @ ca.jtimes(rotation, theta, theta_dot)
    velocity = euler.rotation(rotation).T @ ca.jtimes(translation, theta, theta_dot)
    subspace = ca.jacobian(ca.vertcat(omega, velocity), u)
    rate = ca.jtimes(subspace @ u, theta, theta_dot)
    return ca.Function(f"motion_{kind}", [theta, u],
                       [rotation, translation, subspace, rate, theta_dot],
                       ["theta", "u"], ["rotation", "translation", "S", "c", "theta_dot"])


class Joint:
    """One tree joint's symbolic quantities: coordinates, velocities (free ones from the state,
    prescribed ones from their drivers), S and c in the child's frame, parent -> child
    transform."""

    def __init__(self, joint: TreeJoint, t, theta_free: dict, u_free: dict):
        """theta_free / u_free: coordinate index -> its state symbol."""
        motion = MOTIONS[joint.type]
        self.joint = joint
        theta = [theta_free.get(c) for c in range(motion.n_q)]
        u = [u_free.get(c) for c in range(motion.n_v)]
        u_dot = [0] * motion.n_v
        for c, (f, sign) in joint.prescribed.items():
            value = sign * f.casadi(t=t)
            rate = ca.jacobian(value, t)
            theta[c], u[c], u_dot[c] = value, rate, ca.jacobian(rate, t)
        self.theta, self.u = ca.vertcat(*theta), ca.vertcat(*u)
        rotation, translation, subspace, rate, self.theta_dot = local_motion(joint.type)(
            self.theta, self.u)
        self.rotation, self.translation = rotation, translation
        s_body = spatial.moved(joint.child_frame, subspace)
        self.free = sorted(u_free)
        self.s_free = s_body[:, self.free]
        known = [c for c in range(motion.n_v) if c not in u_free]
        self.relative = s_body @ self.u  # S u: the joint's share of the child's V
        self.c_joint = spatial.moved(joint.child_frame, rate)  # + S u_dot of the prescribed
        if known:
            self.c_joint += s_body[:, known] @ ca.vertcat(*[u_dot[c] for c in known])
        # parent -> child: E = (C_p R_rel C_c^T)^T, child origin s_p + C_p d - E^T s_c
        c_p, s_p = (ca.DM(v) for v in joint.parent_frame)
        c_c, s_c = (ca.DM(v) for v in joint.child_frame)
        e = (c_p @ euler.rotation(rotation) @ c_c.T).T
        self.e, self.r = e, s_p + c_p @ translation - e.T @ s_c
        self.x = spatial.transform(self.e, self.r)


@dataclass(frozen=True)
class Kinematics:
    """Global poses and spatial velocities of every body (IR order) on the tree."""

    r: list
    p: list
    rotation: list
    velocity: list  # V per body (body frame, at the CM)

    def r_dot(self, k: int):
        return self.rotation[k] @ self.velocity[k][3:6]

    def p_dot(self, k: int):
        return 0.5 * euler.g_matrix(self.p[k]).T @ self.velocity[k][0:3]


def kinematics(joints: list[Joint], n_bodies: int) -> Kinematics:
    r, p, rot, vel = ([None] * n_bodies for _ in range(4))
    for j in joints:
        tj = j.joint
        if tj.parent == GROUND_INDEX:
            r_p, p_p, rot_p, v_p = ca.DM.zeros(3), ca.DM(GROUND_POSE[3:]), ca.DM.eye(3), None
        else:
            r_p, p_p, rot_p, v_p = r[tj.parent], p[tj.parent], rot[tj.parent], vel[tj.parent]
        (c_p, s_p), (c_c, s_c) = tj.parent_frame, tj.child_frame
        p_k = product(product(product(p_p, ca.DM(from_matrix(c_p))), j.rotation),
                      conjugate(ca.DM(from_matrix(c_c))))
        rot_k = euler.rotation(p_k)
        r_k = r_p + rot_p @ (ca.DM(s_p) + ca.DM(c_p) @ j.translation) - rot_k @ ca.DM(s_c)
        v_k = j.relative if v_p is None else j.x @ v_p + j.relative
        r[tj.child], p[tj.child], rot[tj.child], vel[tj.child] = r_k, p_k, rot_k, v_k
    return Kinematics(r, p, rot, vel)


def state(kin: Kinematics, n_bodies: int) -> tuple:
    """The r-p (q, q_dot) of the tree's state."""
    q = ca.vertcat(*kin.r, *kin.p)
    q_dot = ca.vertcat(*[kin.r_dot(k) for k in range(n_bodies)],
                       *[kin.p_dot(k) for k in range(n_bodies)])
    return q, q_dot


def applied_wrenches(ir: ModelIR, t, kin: Kinematics) -> list:
    """Body wrenches (n_bar, A^T F) of every applied force at the tree's state."""
    nb = ir.n_bodies
    x = Coordinates.create(nb)
    generalized, _ = eom.applied_forces(ir, x)
    applied = ca.Function("applied", [x.t, x.q, x.q_dot, x.q_ground], [generalized])
    forces = applied(t, *state(kin, nb), ca.DM(GROUND_POSE))
    wrenches = []
    for k in range(nb):
        f_global = forces[3 * k:3 * k + 3]
        torque = 0.5 * euler.g_matrix(kin.p[k]) @ forces[3 * nb + 4 * k:3 * nb + 4 * k + 4]
        wrenches.append(ca.vertcat(torque, kin.rotation[k].T @ f_global))
    return wrenches


@dataclass(frozen=True)
class Dynamics:
    """What the articulated-body algorithm gives: per tree joint its free accelerations, per
    body its spatial acceleration, and the bias forces and inertias the wrench pass reuses."""

    u_dot: list
    accelerations: list
    bias: list
    inertia: list


def articulated_body(ir: ModelIR, joints: list[Joint], kin: Kinematics, external: list,
                     torques: list) -> Dynamics:
    """The accelerations under applied body wrenches `external` and generalized forces
    `torques` (per joint, along its free velocities)."""
    nb = ir.n_bodies
    inertia = [spatial.inertia(b.mass, b.inertia) for b in ir.bodies]
    bias, c, art_inertia, art_bias = [None] * nb, [None] * nb, [None] * nb, [None] * nb
    for j in joints:  # pass 1, root to leaves: velocity-product terms
        k = j.joint.child
        v = kin.velocity[k]
        c[k] = j.c_joint + spatial.cross_motion(v, j.relative)
        bias[k] = spatial.cross_force(v, inertia[k] @ v) - external[k]
        art_inertia[k], art_bias[k] = ca.SX(inertia[k]), bias[k]
    solved = {}
    for j, tau in zip(reversed(joints), reversed(torques), strict=True):  # pass 2
        k, parent = j.joint.child, j.joint.parent
        ia, pa = art_inertia[k], art_bias[k]
        if j.free:
            u_mat = ia @ j.s_free
            d_inv = ca.inv(j.s_free.T @ u_mat)
            residual = tau - j.s_free.T @ pa
            solved[k] = (u_mat, d_inv, residual)
            ia = ia - u_mat @ d_inv @ u_mat.T
            pa = pa + ia @ c[k] + u_mat @ (d_inv @ residual)
        else:
            pa = pa + ia @ c[k]
        if parent != GROUND_INDEX:
            art_inertia[parent] = art_inertia[parent] + spatial.transformed_inertia(
                j.e, j.r, ia)
            art_bias[parent] = art_bias[parent] + j.x.T @ pa
    accelerations, u_dot = [None] * nb, []
    for j in joints:  # pass 3, root to leaves
        k, parent = j.joint.child, j.joint.parent
        a = c[k] if parent == GROUND_INDEX else j.x @ accelerations[parent] + c[k]
        if k in solved:
            u_mat, d_inv, residual = solved[k]
            u_dot.append(d_inv @ (residual - u_mat.T @ a))
            a = a + j.s_free @ u_dot[-1]
        else:
            u_dot.append(ca.SX(0, 1))
        accelerations[k] = a
    return Dynamics(u_dot, accelerations, bias, inertia)


def joint_wrenches(joints: list[Joint], dynamics: Dynamics) -> list:
    """The wrench each tree joint exerts on its child (child frame, at its CM): the
    Newton-Euler balance of the child's subtree, per joint in tree order."""
    wrench = {}
    for j in reversed(joints):
        k, parent = j.joint.child, j.joint.parent
        wrench[k] = (wrench.get(k, 0) + dynamics.inertia[k] @ dynamics.accelerations[k]
                     + dynamics.bias[k])
        if parent != GROUND_INDEX:
            wrench[parent] = wrench.get(parent, 0) + j.x.T @ wrench[k]
    return [wrench[j.joint.child] for j in joints]
