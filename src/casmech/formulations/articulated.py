"""The recursions of the joint formulation over a spanning tree (formulations/tree.py), in SX and
O(N) in the number of bodies: forward kinematics, the articulated-body algorithm (Featherstone,
Rigid Body Dynamics Algorithms, 2008, table 7.1) and the backward Newton-Euler pass that gives
each tree joint's constraint wrench.

Spatial vectors are per body, in its frame at its CM, angular part first (core/spatial.py):
velocity V = (omega_bar, A^T r_dot), inertia [[J_bar, 0], [0, m 1]], force (n_bar, A^T F). A
tree joint's motion subspace S and the rate term c_J = S_dot u come from AD of its registry
entry (casmech.elements.joint_types.MOTIONS). Applied forces are the r-p ones (eom.applied_forces:
gravity, force elements, effort motors) evaluated on the tree's poses and velocities, as body
wrenches, but for the elements local to one tree joint, which act as generalized forces on its
coordinates (formulations/joint_forces.py); a driver's coordinate is a function of time (its
rate and acceleration by AD). The quantities of the model alone (frames, their quaternions,
inertias in reference frames) go through a joint_constants.Constants: numbers in a numeric
build, symbols computed once per parameter value in a parametric one. Each pass's work on one
body is a step traced once per structure and evaluated inside CasADi (core/traced_steps.py).
"""

from __future__ import annotations

from functools import cache, cached_property

import casadi as ca

from casmech.core import spatial
from casmech.core.quaternions import conjugate, product
from casmech.core.records import record
from casmech.core.traced_steps import traced
from casmech.elements.joint_types import MOTIONS
from casmech.equations import body
from casmech.equations.derivatives import GROUND_POSE
from casmech.equations.symbols import Coordinates
from casmech.formulations.joint_constants import Constants
from casmech.formulations.tree import Frame, TreeJoint
from casmech.model.ir import GROUND_INDEX, ModelIR


@cache
def local_motion(kind: str) -> ca.Function:
    """(theta, u) -> (rotation quaternion, translation, S_J, c_J, theta_dot, rotation matrix)
    of a joint type: S_J maps u to the twist of F_c relative to F_p in F_c coordinates
    (angular first, the origin's velocity second), c_J = S_J_dot u."""
    motion = MOTIONS[kind]
    theta, u = ca.SX.sym("theta", motion.n_q), ca.SX.sym("u", motion.n_v)
    rotation, translation = motion.rotation(theta), motion.translation(theta)
    matrix = motion.matrix(theta)
    theta_dot = motion.rates(theta, u)
    omega = motion.angular_velocity(theta, u)
    if omega is None:
        omega = body.angular_velocity(rotation, ca.jtimes(rotation, theta, theta_dot))
    velocity = matrix.T @ ca.jtimes(translation, theta, theta_dot)
    subspace = ca.jacobian(ca.vertcat(omega, velocity), u)
    rate = ca.jtimes(subspace @ u, theta, theta_dot)
    return ca.Function(f"motion_{kind}", [theta, u],
                       [rotation, translation, subspace, rate, theta_dot, matrix],
                       ["theta", "u"], ["rotation", "translation", "S", "c", "theta_dot",
                                        "matrix"])


NUMERIC = Constants()  # a numeric build's: every constant a casadi.DM


def to_center(frame: Frame, constants: Constants = NUMERIC) -> tuple:
    """(E, r) of the motion transform from a body's reference frame to its CM frame."""
    if not constants.symbolic:
        return constants.once("center", frame, _numeric_center)
    return constants.once("center", frame, lambda f: (constants(f[0]),
                                                       constants(-ca.SX(f[0]).T @ f[1])))


def _numeric_center(frame: Frame) -> tuple:
    axes, origin = (ca.DM(v) for v in frame)
    return axes, -axes.T @ origin


class Joint:
    """One tree joint's symbolic quantities: coordinates, velocities (free ones from the state,
    prescribed ones from their drivers), and in the child's reference frame F_c (its joint
    frame: origin at the joint point) S, c_J and the transform from the parent's reference
    frame (ground, or the child frame of the parent's own tree joint)."""

    def __init__(self, joint: TreeJoint, t, theta_free: dict, u_free: dict,
                 parent_reference: Frame | None, constants: Constants = NUMERIC):
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
        rotation, translation, subspace, rate, self.theta_dot, matrix = local_motion(
            joint.type)(self.theta, self.u)
        self.rotation, self.translation, self.matrix = rotation, translation, matrix
        self.free = sorted(u_free)
        self.s_free = subspace[:, self.free]
        self.selection = spatial.selection(self.s_free)  # rows S selects, when it does
        known = [c for c in range(motion.n_v) if c not in u_free]
        self.relative = subspace @ self.u  # S u: the joint's share of the child's V
        self.c_joint = rate  # + S u_dot of the prescribed velocities
        if known:
            self.c_joint += subspace[:, known] @ ca.vertcat(*[u_dot[c] for c in known])
        # parent reference -> F_p (constant), then F_p -> F_c (the joint's motion)
        c_p, s_p = (constants.raw(v) for v in joint.parent_frame)
        if parent_reference is None:  # ground: the global frame
            e_t, r_t = constants(c_p.T), constants(s_p)
        else:
            c_ref, o_ref = (constants.raw(v) for v in parent_reference)
            e_t, r_t = constants(c_p.T @ c_ref), constants(c_ref.T @ (s_p - o_ref))
        self.e, self.r = _joint_transform(matrix, translation, e_t, r_t)


@traced
def _joint_transform(matrix, translation, e_t, r_t):
    """(E, r) of the motion transform from the parent's reference frame to the child's: the
    constant one (e_t, r_t) to F_p, then the joint's motion (its rotation matrix)."""
    return matrix.T @ e_t, r_t + e_t.T @ translation


@record
class Kinematics:
    """Global poses, and spatial velocities of every body (IR order) on the tree: V in the
    body's reference frame, `velocity` in its CM frame (body axes). The rotation matrices
    compose the joints' (of cos and sin of their angles); the Euler parameters `p` are
    composed from the joints' quaternions when read (results rows, forces of r-p
    coordinates), so a graph that does not read them has no half-angle terms."""

    r: list
    rotation: list
    frame_velocity: list
    frames: list  # each body's reference frame (the child frame of its tree joint)
    constants: Constants
    # per tree joint, root to leaves: (child, parent, parent frame's quaternion, the joint's
    # rotation quaternion, child frame's quaternion)
    turns: tuple

    @cached_property
    def p(self) -> list:
        p = [None] * len(self.r)
        for child, parent, q_cp, rotation, q_cc in self.turns:
            p_p = GROUND_STATE[1] if parent == GROUND_INDEX else p[parent]
            p[child] = _orientation(p_p, q_cp, rotation, q_cc)[0]
        return p

    @cached_property
    def velocity(self) -> list:
        return [_moved(*to_center(f, self.constants), v)[0]
                for f, v in zip(self.frames, self.frame_velocity, strict=True)]

    @cached_property
    def rates(self) -> list:
        """(r_dot, p_dot) of every body."""
        return [_rates(rot, p, v) for rot, p, v in zip(self.rotation, self.p, self.velocity,
                                                       strict=True)]

    def r_dot(self, k: int):
        return self.rates[k][0]

    def p_dot(self, k: int):
        return self.rates[k][1]


def kinematics(joints: list[Joint], n_bodies: int, constants: Constants = NUMERIC
               ) -> Kinematics:
    r, rot, vel, frames = ([None] * n_bodies for _ in range(4))
    turns = []
    for j in joints:
        tj = j.joint
        if tj.parent == GROUND_INDEX:
            r_p, _, rot_p, v_p = GROUND_STATE
        else:
            r_p, rot_p, v_p = r[tj.parent], rot[tj.parent], vel[tj.parent]
        (c_p, s_p), (c_c, s_c) = tj.parent_frame, tj.child_frame
        rot[tj.child], r[tj.child], vel[tj.child] = _link(
            r_p, rot_p, v_p, constants(s_p), constants(c_p), constants(c_c), constants(s_c),
            j.matrix, j.translation, j.e, j.r, j.relative)
        frames[tj.child] = tj.child_frame
        turns.append((tj.child, tj.parent, constants.quaternion(c_p), j.rotation,
                      constants.quaternion(c_c)))
    return Kinematics(r, rot, vel, frames, constants, tuple(turns))


# ground's (r, p, A, V): the global frame at rest
GROUND_STATE = (ca.DM.zeros(3), ca.DM(GROUND_POSE[3:]), ca.DM.eye(3), ca.DM.zeros(6))


@traced
def _link(r_p, rot_p, v_p, s_p, c_p, c_c, s_c, matrix, translation, e, r, relative):
    """A child's (A, r, V) from its parent's and its tree joint's motion: A = A_p C_p R C_c^T
    with R the joint's rotation matrix."""
    rot_k = rot_p @ (c_p @ matrix @ c_c.T)
    r_k = r_p + rot_p @ (s_p + c_p @ translation) - rot_k @ s_c
    return rot_k, r_k, spatial.motion(e, r, v_p) + relative


@traced
def _orientation(p_p, q_cp, rotation, q_cc):
    """A child's Euler parameters p_p (x) q_cp (x) rotation (x) conj(q_cc)."""
    return (product(product(product(p_p, q_cp), rotation), conjugate(q_cc)),)


@traced
def _moved(e, r, m):
    """spatial.motion as a traced step."""
    return (spatial.motion(e, r, m),)


@traced
def _rates(rotation, p, velocity):
    """A body's (r_dot, p_dot) from its CM-frame spatial velocity."""
    return rotation @ velocity[3:6], body.p_dot(p, velocity[0:3])


def state(kin: Kinematics, n_bodies: int) -> tuple:
    """The r-p (q, q_dot) of the tree's state."""
    q = ca.vertcat(*kin.r, *kin.p)
    q_dot = ca.vertcat(*[kin.r_dot(k) for k in range(n_bodies)],
                       *[kin.p_dot(k) for k in range(n_bodies)])
    return q, q_dot


def applied_wrenches(ir: ModelIR, t, kin: Kinematics) -> list:
    """Body wrenches (n_bar, A^T F) of every applied force at the tree's state (a parametric
    IR's forces over its model data, kin.constants.data)."""
    from casmech.equations import eom

    nb = ir.n_bodies
    x = Coordinates.create(nb)
    generalized, _ = eom.applied_forces(ir, x)
    data = [kin.constants.data] if kin.constants.symbolic else []
    applied = ca.Function("applied", [x.t, x.q, x.q_dot, x.q_ground, *data], [generalized])
    forces = applied(t, *state(kin, nb), ca.DM(GROUND_POSE), *data)
    parts = ca.vertsplit(forces, [*range(0, 3 * nb, 3), *range(3 * nb, 7 * nb + 1, 4)])
    return [_wrench(kin.p[k], kin.rotation[k], parts[k], parts[nb + k])[0] for k in range(nb)]


@traced
def _wrench(p, rotation, force, q_p):
    """A body's wrench (n_bar, A^T F) of its generalized forces (global force, on p)."""
    return (ca.vertcat(body.moment(p, q_p), rotation.T @ force),)


@record
class Dynamics:
    """What the articulated-body algorithm gives: per tree joint its free accelerations, per
    body its spatial acceleration (reference frame; `accelerations`: CM frame) and what the
    wrench pass reuses (bias forces, inertias, in the reference frames)."""

    u_dot: list
    frame_accelerations: list
    bias: list
    inertia: list
    frames: list
    constants: Constants

    @cached_property
    def accelerations(self) -> list:
        return [_moved(*to_center(f, self.constants), a)[0]
                for f, a in zip(self.frames, self.frame_accelerations, strict=True)]


def reference_inertia(mass, inertia, frame: Frame, constants: Constants = NUMERIC):
    """A body's spatial inertia in its reference frame (a constant of the model)."""
    if not constants.symbolic:
        e, r = to_center(frame, constants)
        return ca.DM(ca.evalf(_transformed_inertia(e, r, spatial.inertia(mass, inertia))[0]))
    axes, origin = (ca.SX(v) for v in frame)
    centred = ca.diagcat(ca.SX(inertia), mass * ca.SX.eye(3))
    return constants(spatial.transformed_inertia(axes, -axes.T @ origin, centred))


def articulated_body(ir: ModelIR, joints: list[Joint], kin: Kinematics, external: list,
                     torques: list) -> Dynamics:
    """The accelerations under applied body wrenches `external` (CM frame) and generalized
    forces `torques` (per joint, along its free velocities). Joints whose motion subspace
    selects coordinates (revolute, sliding, spherical: most) are eliminated blockwise, so the
    articulated inertia's eliminated rows are exact zeros: the generic IA - U D^-1 U^T left
    roundoff there that grew by ~2.5x per body along a chain with a small axial inertia (a
    48-link chain: accelerations 1.6e-2 off)."""
    nb, constants = ir.n_bodies, kin.constants
    frames = kin.frames
    inertia = [reference_inertia(b.mass, b.inertia, frames[k], constants)
               for k, b in enumerate(ir.bodies)]
    bias, c, art_inertia, art_bias = [None] * nb, [None] * nb, [None] * nb, [None] * nb
    for j in joints:  # pass 1, root to leaves: velocity-product terms
        k = j.joint.child
        c[k], bias[k] = _velocity_terms(kin.frame_velocity[k], j.c_joint, j.relative,
                                        inertia[k], *to_center(frames[k], constants),
                                        external[k])
        art_inertia[k], art_bias[k] = ca.SX(inertia[k]), bias[k]
    solved = {}
    for j, tau in zip(reversed(joints), reversed(torques), strict=True):  # pass 2
        k, parent = j.joint.child, j.joint.parent
        to_parent = parent != GROUND_INDEX
        out = _articulated(art_inertia[k], art_bias[k], c[k], tau, j.s_free, j.e, j.r,
                           *((art_inertia[parent], art_bias[parent]) if to_parent else ()),
                           rows=None if j.selection is None else tuple(j.selection),
                           free=bool(j.free))
        if j.free:
            solved[k] = out[:3]
        if to_parent:
            art_inertia[parent], art_bias[parent] = out[-2:]
    accelerations, u_dot = [None] * nb, []
    for j in joints:  # pass 3, root to leaves
        k, parent = j.joint.child, j.joint.parent
        a_parent = ca.DM.zeros(6) if parent == GROUND_INDEX else accelerations[parent]
        if k in solved:
            accelerations[k], u = _accelerate(a_parent, c[k], j.e, j.r, j.s_free, *solved[k])
            u_dot.append(u)
        else:
            accelerations[k] = _accelerate(a_parent, c[k], j.e, j.r)[0]
            u_dot.append(ca.SX(0, 1))
    return Dynamics(u_dot, accelerations, bias, inertia, frames, constants)


@traced
def _velocity_terms(v, c_joint, relative, inertia, e_c, r_c, external):
    """Pass 1 of a body: its velocity-product acceleration c and bias force."""
    return (c_joint + spatial.cross_motion(v, relative),
            spatial.cross_force(v, inertia @ v) - spatial.force_back(e_c, r_c, external))


@traced
def _articulated(ia, pa, c, tau, s_free, e, r, *parent, rows, free):
    """Pass 2 of a body: (U, D^-1, residual) when its joint has free velocities, then its
    parent's articulated inertia and bias with the body's added (`parent` given)."""
    solved = ()
    if free:
        ia, pa, solved = eliminate(s_free, rows, ia, pa, c, tau)
    else:
        pa = pa + ia @ c
    if not parent:
        return solved
    ia_parent, pa_parent = parent
    return (*solved, ia_parent + spatial.transformed_inertia(e, r, ia),
            pa_parent + spatial.force_back(e, r, pa))


@traced
def _accelerate(a_parent, c, e, r, *solved):
    """Pass 3 of a body: its spatial acceleration, and its free accelerations when `solved`
    = (S, U, D^-1, residual) is given."""
    a = spatial.motion(e, r, a_parent) + c
    if not solved:
        return (a,)
    s_free, u_mat, d_inv, residual = solved
    u_dot = d_inv @ (residual - u_mat.T @ a)
    return a + s_free @ u_dot, u_dot


def eliminate(s_free, rows, ia, pa, c, tau):
    """The articulated inertia and bias a joint passes on, and (U, D^-1, residual) for pass 3;
    rows: the rows S selects (spatial.selection), if it does; tau: the joint's generalized
    forces along S."""
    if rows is None:
        u_mat = ia @ s_free
        d_inv = ca.inv(s_free.T @ u_mat)
        residual = tau - s_free.T @ pa
        ia = ia - u_mat @ d_inv @ u_mat.T
    else:
        rows = list(rows)
        rest = [r for r in range(6) if r not in rows]
        u_mat = ia[:, rows]
        d_inv = ca.inv(ia[rows, rows])
        residual = tau - pa[rows]
        reduced = ca.SX.zeros(6, 6)
        reduced[rest, rest] = ia[rest, rest] - ia[rest, rows] @ d_inv @ ia[rows, rest]
        ia = reduced
    pa = pa + ia @ c + u_mat @ (d_inv @ residual)
    return ia, pa, (u_mat, d_inv, residual)


def joint_wrenches(joints: list[Joint], dynamics: Dynamics, applied: list | None = None
                   ) -> list:
    """The wrench each tree joint exerts on its child (CM frame, body axes): the Newton-Euler
    balance of the child's subtree, per joint in tree order; `applied`: further body wrenches
    (CM frame) that the dynamics took as joint forces (formulations/joint_forces.py), in the
    balance as applied forces."""
    wrench, zero = {}, ca.DM.zeros(6)
    constants = dynamics.constants
    for j in reversed(joints):
        k, parent = j.joint.child, j.joint.parent
        bias = dynamics.bias[k]
        if applied is not None:
            bias = _less(bias, *to_center(dynamics.frames[k], constants), applied[k])[0]
        wrench[k], back = _subtree(wrench.get(k, zero), dynamics.inertia[k],
                                   dynamics.frame_accelerations[k], bias, j.e, j.r)
        if parent != GROUND_INDEX:
            wrench[parent] = wrench.get(parent, zero) + back
    return [at_center(*(constants(v) for v in dynamics.frames[j.joint.child]),
                       wrench[j.joint.child])[0] for j in joints]


@traced
def _less(bias, e_c, r_c, applied):
    """A body's bias force less an applied body wrench (CM frame), as _velocity_terms takes
    one."""
    return (bias - spatial.force_back(e_c, r_c, applied),)


@traced
def _subtree(children, inertia, acceleration, bias, e, r):
    """The wrench a body's joint exerts on it (its children's, `children`, in its reference
    frame), and that wrench in the parent's reference frame."""
    wrench = children + inertia @ acceleration + bias
    return wrench, spatial.force_back(e, r, wrench)


@traced
def at_center(axes, origin, f):
    """A force in a body's reference frame, at its CM in body axes."""
    lin = axes @ f[3:6]
    return (ca.vertcat(axes @ f[0:3] + ca.cross(origin, lin), lin),)


@traced
def _transformed_inertia(e, r, inertia):
    """spatial.transformed_inertia as a traced step."""
    return (spatial.transformed_inertia(e, r, inertia),)
