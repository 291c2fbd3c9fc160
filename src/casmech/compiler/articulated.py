"""Equations of motion in joint coordinates over a spanning tree (compiler/tree.py): forward
kinematics and the articulated-body algorithm (Featherstone, Rigid Body Dynamics Algorithms,
2008, table 7.1) written once in SX, O(N) in the number of bodies.

Spatial vectors are per body, in its frame at its CM, angular part first: velocity
V = (omega_bar, A^T r_dot), inertia I = [[J_bar, 0], [0, m 1]], force (n_bar, A^T F). A tree
joint's motion subspace S and the rate term c_J = S_dot u come from AD of its registry entry's
maps (compiler/joint_motions.py). Applied forces are the r-p ones (eom.applied_forces: gravity,
force elements, effort motors), evaluated on the poses and velocities the tree gives, as body
wrenches; a driver's coordinate is a function of time (its rate and acceleration by AD).

The state is x = [theta; u] over the coordinates and velocities no driver prescribes.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache, cached_property

import casadi as ca
import numpy as np

from casmech.compiler import eom, euler, lazy_jacobian
from casmech.compiler.assemble import Coordinates, build_constraints
from casmech.compiler.ir import GROUND_INDEX, ModelIR
from casmech.compiler.joint_motions import MOTIONS, from_matrix, product
from casmech.compiler.tree import Tree, TreeJoint


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
    twist = ca.vertcat(omega, velocity)
    subspace = ca.jacobian(twist, u)
    rate = ca.jtimes(subspace @ u, theta, theta_dot)
    return ca.Function(f"motion_{kind}", [theta, u],
                       [rotation, translation, subspace, rate, theta_dot],
                       ["theta", "u"], ["rotation", "translation", "S", "c", "theta_dot"])


def to_body(frame, motion):
    """A motion vector (6 x k) at F_c's origin in F_c coordinates -> at the CM, body frame."""
    axes, origin = (ca.DM(v) for v in frame)
    omega = axes @ motion[0:3, :]
    velocity = axes @ motion[3:6, :] - ca.cross(omega, ca.repmat(origin, 1, motion.size2()))
    return ca.vertcat(omega, velocity)


def cross_motion(v, m):
    """v x m for motion vectors (6x1)."""
    w, lin = v[0:3], v[3:6]
    return ca.vertcat(ca.cross(w, m[0:3]), ca.cross(w, m[3:6]) + ca.cross(lin, m[0:3]))


def cross_force(v, f):
    """v x* f for a motion vector v and a force f."""
    w, lin = v[0:3], v[3:6]
    return ca.vertcat(ca.cross(w, f[0:3]) + ca.cross(lin, f[3:6]), ca.cross(w, f[3:6]))


def transform(e, r):
    """Plucker motion transform parent -> child: e rotates parent to child coordinates, r is
    the child's origin in parent coordinates."""
    zero = ca.SX.zeros(3, 3)
    return ca.vertcat(ca.horzcat(e, zero), ca.horzcat(-e @ euler.skew(r), e))


def spatial_inertia(mass: float, inertia: np.ndarray) -> ca.DM:
    return ca.DM(np.block([[inertia, np.zeros((3, 3))], [np.zeros((3, 3)), mass * np.eye(3)]]))


@dataclass(frozen=True)
class Layout:
    """Which coordinates and velocities are states: per tree joint, the slices of x."""

    theta: tuple[tuple[int, ...], ...]  # per joint: indices into x of its free coordinates
    u: tuple[tuple[int, ...], ...]  # per joint: indices into x of its free velocities
    free_theta: tuple[tuple[int, ...], ...]  # per joint: which of its coordinates are free
    free_u: tuple[tuple[int, ...], ...]
    n_x: int


def layout(tree: Tree) -> Layout:
    free_theta = [tuple(c for c in range(MOTIONS[j.type].n_q) if c not in j.prescribed)
                  for j in tree.joints]
    free_u = [tuple(c for c in range(MOTIONS[j.type].n_v) if c not in j.prescribed)
              for j in tree.joints]
    theta, n = [], 0
    for free in free_theta:
        theta.append(tuple(range(n, n + len(free))))
        n += len(free)
    u = []
    for free in free_u:
        u.append(tuple(range(n, n + len(free))))
        n += len(free)
    return Layout(tuple(theta), tuple(u), tuple(free_theta), tuple(free_u), n)


class _Joint:
    """One tree joint's symbolic quantities (coordinates, velocities, S, c, transform)."""

    def __init__(self, joint: TreeJoint, t, x, theta_index, u_index, free_theta, free_u):
        motion = MOTIONS[joint.type]
        self.joint = joint
        theta, u, u_dot = ([None] * motion.n_q, [None] * motion.n_v, [0] * motion.n_v)
        for c, k in zip(free_theta, theta_index, strict=True):
            theta[c] = x[k]
        for c, k in zip(free_u, u_index, strict=True):
            u[c] = x[k]
        for c, (f, sign) in joint.prescribed.items():
            value = sign * f.casadi(t=t)
            rate = ca.jacobian(value, t)
            theta[c], u[c], u_dot[c] = value, rate, ca.jacobian(rate, t)
        self.theta, self.u = ca.vertcat(*theta), ca.vertcat(*u)
        rotation, translation, subspace, rate, self.theta_dot = local_motion(joint.type)(
            self.theta, self.u)
        self.rotation, self.translation = rotation, translation
        s_body = to_body(joint.child_frame, subspace)
        self.s_free = s_body[:, list(free_u)]
        known = [c for c in range(motion.n_v) if c not in free_u]
        self.relative = s_body @ self.u  # S u, the joint's contribution to V
        self.c_joint = to_body(joint.child_frame, rate)  # + S u_dot of prescribed velocities
        if known:
            self.c_joint += s_body[:, known] @ ca.vertcat(*[u_dot[c] for c in known])
        # parent -> child transform: E = (C_p R_rel C_c^T)^T, r = s_p + C_p d - E^T s_c
        c_p, s_p = (ca.DM(v) for v in joint.parent_frame)
        c_c, s_c = (ca.DM(v) for v in joint.child_frame)
        e = (c_p @ euler.rotation(rotation) @ c_c.T).T
        self.x = transform(e, s_p + c_p @ translation - e.T @ s_c)


@dataclass(frozen=True)
class Kinematics:
    """Global poses and spatial velocities of every body (IR order) on the tree."""

    r: list
    p: list
    rotation: list
    velocity: list  # V per body (body frame, at the CM)


def kinematics(tree: Tree, joints: list[_Joint], n_bodies: int) -> Kinematics:
    r, p, rot, vel = ([None] * n_bodies for _ in range(4))
    for j in joints:
        tj = j.joint
        if tj.parent == GROUND_INDEX:
            r_p, p_p, rot_p, v_p = ca.DM.zeros(3), ca.DM([1, 0, 0, 0]), ca.DM.eye(3), None
        else:
            r_p, p_p, rot_p, v_p = r[tj.parent], p[tj.parent], rot[tj.parent], vel[tj.parent]
        c_p, s_p = tj.parent_frame
        c_c, s_c = tj.child_frame
        q_p, q_c = ca.DM(from_matrix(c_p)), ca.DM(from_matrix(c_c))
        conj_c = ca.vertcat(q_c[0], -q_c[1:4])
        p_k = product(product(product(p_p, q_p), j.rotation), conj_c)
        rot_k = euler.rotation(p_k)
        r_k = r_p + rot_p @ (ca.DM(s_p) + ca.DM(c_p) @ j.translation) - rot_k @ ca.DM(s_c)
        v_k = j.relative if v_p is None else j.x @ v_p + j.relative
        r[tj.child], p[tj.child], rot[tj.child], vel[tj.child] = r_k, p_k, rot_k, v_k
    return Kinematics(r, p, rot, vel)


def applied_wrenches(ir: ModelIR, t, kin: Kinematics) -> list:
    """Body wrenches (n_bar, A^T F) of every applied force at the tree's state."""
    nb = ir.n_bodies
    x = Coordinates.create(nb)
    generalized, _ = eom.applied_forces(ir, x)
    applied = ca.Function("applied", [x.t, x.q, x.q_dot, x.q_ground],
                          [generalized])
    q = ca.vertcat(*kin.r, *kin.p)
    r_dot = [kin.rotation[k] @ kin.velocity[k][3:6] for k in range(nb)]
    p_dot = [0.5 * euler.g_matrix(kin.p[k]).T @ kin.velocity[k][0:3] for k in range(nb)]
    forces = applied(t, q, ca.vertcat(*r_dot, *p_dot), ca.DM([0, 0, 0, 1, 0, 0, 0]))
    wrenches = []
    for k in range(nb):
        f_global = forces[3 * k:3 * k + 3]
        q_p = forces[3 * nb + 4 * k:3 * nb + 4 * k + 4]
        torque = 0.5 * euler.g_matrix(kin.p[k]) @ q_p
        wrenches.append(ca.vertcat(torque, kin.rotation[k].T @ f_global))
    return wrenches


def articulated_body(ir: ModelIR, joints: list[_Joint], kin: Kinematics, external: list):
    """(accelerations of the free velocities per joint, spatial accelerations per body)."""
    nb = ir.n_bodies
    inertia = [spatial_inertia(b.mass, b.inertia) for b in ir.bodies]
    bias, c, art_inertia, art_bias = [None] * nb, [None] * nb, [None] * nb, [None] * nb
    for j in joints:
        k = j.joint.child
        v = kin.velocity[k]
        c[k] = j.c_joint + cross_motion(v, j.relative)
        bias[k] = cross_force(v, inertia[k] @ v) - external[k]
        art_inertia[k], art_bias[k] = ca.SX(inertia[k]), bias[k]
    solved = {}
    for j in reversed(joints):  # pass 2, leaves to root
        k, parent = j.joint.child, j.joint.parent
        ia, pa = art_inertia[k], art_bias[k]
        s = j.s_free
        if s.size2():
            u_mat = ia @ s
            d_inv = ca.inv(s.T @ u_mat)
            tau = -s.T @ pa
            solved[k] = (u_mat, d_inv, tau)
            ia_a = ia - u_mat @ d_inv @ u_mat.T
            pa_a = pa + ia_a @ c[k] + u_mat @ (d_inv @ tau)
        else:
            ia_a, pa_a = ia, pa + ia @ c[k]
        if parent != GROUND_INDEX:
            art_inertia[parent] = art_inertia[parent] + j.x.T @ ia_a @ j.x
            art_bias[parent] = art_bias[parent] + j.x.T @ pa_a
    accelerations, u_dot = [None] * nb, []
    for j in joints:  # pass 3, root to leaves
        k, parent = j.joint.child, j.joint.parent
        a = c[k] if parent == GROUND_INDEX else j.x @ accelerations[parent] + c[k]
        if k in solved:
            u_mat, d_inv, tau = solved[k]
            ddq = d_inv @ (tau - u_mat.T @ a)
            a = a + j.s_free @ ddq
            u_dot.append(ddq)
        else:
            u_dot.append(ca.SX(0, 1))
        accelerations[k] = a
    return u_dot, accelerations, bias, inertia


def joint_wrenches(joints: list[_Joint], accelerations, bias, inertia) -> list:
    """The wrench each tree joint's constraint exerts on its child (child frame, at its CM):
    the Newton-Euler balance of the child's subtree (the backward pass of the recursive
    Newton-Euler algorithm), per joint in tree order."""
    wrench = {}
    for j in reversed(joints):
        k = j.joint.child
        wrench[k] = wrench.get(k, 0) + inertia[k] @ accelerations[k] + bias[k]
        if j.joint.parent != GROUND_INDEX:
            wrench[j.joint.parent] = wrench.get(j.joint.parent, 0) + j.x.T @ wrench[k]
    return [wrench[j.joint.child] for j in joints]


def tree_multipliers(ir: ModelIR, joints: list[_Joint], t, q, kin: Kinematics,
                     wrenches: list):
    """Multipliers of every joint row (normalization rows 0): each tree joint's rows solve
    -B^T lam = w for its constraint wrench w on the child, B the rows' r-omega Jacobian
    [Phi_r, Pi_bar] at the child (global force, body-frame torque)."""
    cs = build_constraints(ir)
    blocks = []
    for j in joints:
        rows, c = list(j.joint.joint.rows), j.joint.child
        blocks.append(ca.horzcat(cs.phi_r[rows, 3 * c:3 * c + 3], cs.pi_bar[rows, 3 * c:3 * c + 3]))
    block = ca.Function("blocks", [cs.x.t, cs.x.q], blocks).call([t, q]) if blocks else []
    lam = ca.SX.zeros(len(ir.row_info()), 1)
    for j, b, w in zip(joints, block, wrenches, strict=True):
        rows, c = list(j.joint.joint.rows), j.joint.child
        force = ca.vertcat(kin.rotation[c] @ w[3:6], w[0:3])
        lam[rows] = -ca.solve(b @ b.T, b @ force)
    return lam


@dataclass(frozen=True)
class JointSystem:
    """The compiled tree: the ODE and the results' state (r-p and r-omega) per time."""

    tree: Tree
    layout: Layout
    ode: ca.Function  # (t, x) -> x_dot
    motion: ca.Function  # (t, x, signs) -> (q, q_dot, q_ddot, lam): a results row's state
    relative: ca.Function  # per joint type: see local_motion (numeric initial conditions)

    @cached_property
    def problem(self) -> dict:
        """casadi.integrator's ODE dictionary (MX, with lazy_jacobian's cheap Jacobian)."""
        return lazy_jacobian.problem(self.ode)


def build(ir: ModelIR, tree: Tree) -> JointSystem:
    lay = layout(tree)
    t, x = ca.SX.sym("t"), ca.SX.sym("x", lay.n_x)
    joints = [_Joint(j, t, x, *parts) for j, *parts in
              zip(tree.joints, lay.theta, lay.u, lay.free_theta, lay.free_u, strict=True)]
    kin = kinematics(tree, joints, ir.n_bodies)
    external = applied_wrenches(ir, t, kin)
    u_dot, accelerations, bias, inertia = articulated_body(ir, joints, kin, external)
    theta_dot = [j.theta_dot[list(free)] if free else ca.SX(0, 1)
                 for j, free in zip(joints, lay.free_theta, strict=True)]
    ode = ca.Function("joint_ode", [t, x], [ca.vertcat(*theta_dot, *u_dot)], ["t", "x"],
                      ["ode"])
    signs = ca.SX.sym("signs", ir.n_bodies)
    nb = ir.n_bodies
    q = ca.vertcat(*kin.r, *[signs[k] * kin.p[k] for k in range(nb)])
    r_dot = [kin.rotation[k] @ kin.velocity[k][3:6] for k in range(nb)]
    omega = [kin.velocity[k][0:3] for k in range(nb)]
    r_ddot = [kin.rotation[k] @ (accelerations[k][3:6] + ca.cross(omega[k],
                                                                   kin.velocity[k][3:6]))
              for k in range(nb)]
    alpha = [accelerations[k][0:3] for k in range(nb)]
    p_dot = [0.5 * euler.g_matrix(q_p).T @ w for q_p, w in zip(_quaternions(q, nb), omega,
                                                                   strict=True)]
    p_ddot = [0.5 * (euler.g_matrix(pd).T @ w + euler.g_matrix(q_p).T @ a)
              for q_p, pd, w, a in zip(_quaternions(q, nb), p_dot, omega, alpha, strict=True)]
    tree_joints = [j for j in joints if j.joint.joint is not None]
    wrenches = joint_wrenches(joints, accelerations, bias, inertia)
    lam = tree_multipliers(ir, tree_joints, t, q, kin,
                           [w for j, w in zip(joints, wrenches, strict=True)
                            if j.joint.joint is not None])
    motion = ca.Function("joint_motion", [t, x, signs],
                         [q, ca.vertcat(*r_dot, *p_dot), ca.vertcat(*r_ddot, *p_ddot), lam],
                         ["t", "x", "signs"], ["q", "q_dot", "q_ddot", "lam"])
    return JointSystem(tree, lay, ode, motion, local_motion)


def _quaternions(q, nb: int) -> list:
    return [q[3 * nb + 4 * k:3 * nb + 4 * k + 4] for k in range(nb)]
