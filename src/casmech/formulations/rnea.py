"""Inverse dynamics of a tree by the recursive Newton-Euler algorithm (Featherstone, Rigid Body
Dynamics Algorithms, 2008, table 5.1), in SX and O(N) in the number of bodies: the joint
forces tau that give the free accelerations u_dot at a state, with every applied force of the
model, the drivers' prescribed motions and the velocity-product terms of formulations/
articulated.py (same frames, same per-body quantities).

Pass 1, root to leaves: a body's spatial acceleration from its parent's, its joint's rate term
c_J plus the velocity product v x (S u) and S u_dot. Pass 2, leaves to
root: the wrench its joint transmits, I a + v x* I v - external + its children's, and tau as
its projection S^T f on the joint's free velocities.

Its derivatives come from CasADi's AD of this graph; forward_derivatives turns them into the
forward dynamics' (formulations/joint_space.py).
"""

from __future__ import annotations

import casadi as ca

from casmech.core import spatial
from casmech.core.traced_steps import traced
from casmech.formulations import articulated
from casmech.formulations.articulated import Joint, Kinematics
from casmech.model.ir import GROUND_INDEX, ModelIR


def inverse_dynamics(ir: ModelIR, joints: list[Joint], kin: Kinematics, external: list,
                     u_dot: list) -> list:
    """The generalized forces per tree joint (along its free velocities; an empty column for a
    joint without any) that give the free accelerations `u_dot` (per joint, same layout) under
    the applied body wrenches `external` (CM frame, articulated.applied_wrenches)."""
    nb, constants, frames = ir.n_bodies, kin.constants, kin.frames
    acceleration, wrench = [None] * nb, [None] * nb
    for j, accel in zip(joints, u_dot, strict=True):  # pass 1, root to leaves
        k, parent = j.joint.child, j.joint.parent
        inertia = articulated.reference_inertia(ir.bodies[k].mass, ir.bodies[k].inertia,
                                                frames[k], constants)
        a_parent = ca.DM.zeros(6) if parent == GROUND_INDEX else acceleration[parent]
        free = (j.s_free, accel) if j.free else ()
        acceleration[k], wrench[k] = _forward(
            a_parent, kin.frame_velocity[k], j.c_joint, j.relative, j.e, j.r, inertia,
            *articulated.to_center(frames[k], constants), external[k], *free)
    torques = [None] * len(joints)
    for index in reversed(range(len(joints))):  # pass 2, leaves to root
        j = joints[index]
        k, parent = j.joint.child, j.joint.parent
        torques[index] = j.s_free.T @ wrench[k] if j.free else ca.SX(0, 1)
        if parent != GROUND_INDEX:
            wrench[parent] = wrench[parent] + _back(j.e, j.r, wrench[k])[0]
    return torques


def forward_derivatives(inverse, acceleration, at, wrt: list) -> list:
    """The derivatives of the forward dynamics a(x) by every symbol x of `wrt` (the inverse
    dynamics' other inputs: q, v, t...), then by tau, from the inverse dynamics
    tau = inverse(x, acceleration) (Carpentier and Mansard 2018): differentiating
    inverse(x, a(x, tau)) = tau gives da/dx = -M^-1 dinverse/dx at acceleration = `at` (the
    forward dynamics' a, an expression or the symbol of a known value) and da/dtau = M^-1,
    with M = dinverse/dacceleration factored once by Cholesky. CasADi differentiates the
    inverse dynamics."""
    nv = acceleration.numel()
    if not nv:
        return [ca.SX(0, x.numel()) for x in wrt] + [ca.SX(0, 0)]
    mass = ca.jacobian(inverse, acceleration)
    if not mass.sparsity().is_symmetric():  # symmetric in value, not always in structure (a
        mass = (mass + mass.T) / 2          # free joint's rows): chol needs both
    upper = ca.chol(mass)  # M = R^T R

    def solve(rhs):
        return ca.solve(upper, ca.solve(upper.T, rhs))

    by = ca.substitute([ca.jacobian(inverse, x) for x in wrt], [acceleration], [at])
    return [-solve(b) for b in by] + [solve(ca.SX.eye(nv))]


@traced
def _forward(a_parent, v, c_joint, relative, e, r, inertia, e_c, r_c, external, *free):
    """Pass 1 of a body (reference frame): its spatial acceleration, the parent's moved plus
    c_J + v x (S u) (+ S u_dot), and its own share I a + v x* I v - external of the wrench its
    joint transmits; `free` = (S, u_dot) when the joint has free velocities."""
    a = spatial.motion(e, r, a_parent) + c_joint + spatial.cross_motion(v, relative)
    if free:
        s_free, u_dot = free
        a = a + s_free @ u_dot
    return a, inertia @ a + spatial.cross_force(v, inertia @ v) - spatial.force_back(
        e_c, r_c, external)


@traced
def _back(e, r, f):
    """spatial.force_back as a traced step."""
    return (spatial.force_back(e, r, f),)
