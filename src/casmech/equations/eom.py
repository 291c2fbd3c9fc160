"""Equations of motion in the r-p form, forces, energy and joint reactions.

r-p form (Haug 1989, ch. 11): M r_ddot + Phi_r^T lam = F and
4 G^T J_bar G p_ddot + Phi_p^T lam + P^T lam_P = 2 G^T n_bar + 8 G_dot^T J_bar G_dot p.
Generalized forces of force elements come from virtual work by AD (casmech.elements.forces.terms),
each
by the law of its casmech.elements.force_types entry (FORCE_ELEMENTS).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from functools import partial

import casadi as ca

from casmech.core import euler
from casmech.core.traced_steps import traced
from casmech.core.values import constant
from casmech.elements.force_types import REGISTRY as FORCE_TYPES
from casmech.equations import body, coordinates, limits, motors
from casmech.equations.assemble import Coordinates
from casmech.model.ir import ModelIR


def mass_matrix(ir: ModelIR, x: Coordinates):
    """blkdiag(m_k I_3 ..., 4 G_k^T J_bar_k G_k ...) (7 nb x 7 nb)."""
    blocks = [b.mass * ca.DM.eye(3) for b in ir.bodies]
    blocks += [body.mass_block(x.p(k), constant(b.inertia)) for k, b in enumerate(ir.bodies)]
    return ca.diagcat(*blocks) if blocks else ca.SX(0, 0)


def quadratic_velocity(ir: ModelIR, x: Coordinates):
    """[0; 8 G_dot^T J_bar G_dot p] for every body (G_dot = G(p_dot))."""
    nb = ir.n_bodies
    return ca.vertcat(ca.SX.zeros(3 * nb, 1), *[
        body.quadratic_velocity(x.p(k), x.p(k, x.q_dot), constant(b.inertia))
        for k, b in enumerate(ir.bodies)])


class _Elements(Mapping):
    """ForceIR type -> its law (force, x) -> (generalized force, potential): the force element
    types of casmech.elements.force_types (their `law`, reading the state through
    equations.coordinates), then the joints' effort motors (ir.motors) and stops (ir.limits)."""

    def __getitem__(self, kind: str) -> Callable:
        entry = FORCE_TYPES.get(kind)
        if entry is not None:
            return partial(entry.law, read=coordinates.values)
        return JOINT_ELEMENTS[kind]

    def __iter__(self) -> Iterator[str]:
        yield from FORCE_TYPES
        yield from JOINT_ELEMENTS

    def __len__(self) -> int:
        return len(FORCE_TYPES) + len(JOINT_ELEMENTS)


class _Inputs(Mapping):
    """ForceIR type -> (input name suffixes, (element, u) -> the element with its law replaced
    by the inputs u) of the elements that may be linearization inputs (runtime/linearize.py):
    effort motors, and the force element types with `inputs`."""

    def __getitem__(self, kind: str) -> tuple:
        entry = FORCE_TYPES.get(kind)
        if entry is not None and entry.inputs:
            return entry.inputs, entry.with_inputs
        return motors.INPUTS[kind]

    def __iter__(self) -> Iterator[str]:
        yield from motors.INPUTS
        yield from (name for name, entry in FORCE_TYPES.items() if entry.inputs)

    def __len__(self) -> int:
        return sum(1 for _ in self)


JOINT_ELEMENTS: dict[str, Callable] = {
    # (lambdas: equations.limits imports this module through coordinates)
    "limit_angle": lambda force, x: limits.generalized_force(force, x),  # stops (ir.limits)
    "limit_displacement": lambda force, x: limits.generalized_force(force, x),
    **motors.FORCE_ELEMENTS,  # effort motors of joints (ir.motors)
}
FORCE_ELEMENTS: Mapping[str, Callable] = _Elements()
INPUT_KINDS: Mapping[str, tuple] = _Inputs()


def gravity(ir: ModelIR):
    """[m_k g ...; 0 (4 nb)]: the generalized force of gravity."""
    return ca.vertcat(*[b.mass * constant(ir.gravity) for b in ir.bodies],
                      ca.DM.zeros(4 * ir.n_bodies))


def applied_forces(ir: ModelIR, x: Coordinates):
    """(generalized applied forces incl. gravity, spring potential energy)."""
    total, potential = gravity(ir), 0.0
    for force in (*ir.forces, *ir.motors, *ir.limits):
        generalized, energy = FORCE_ELEMENTS[force.type](force, x)
        total, potential = total + generalized, potential + energy
    return total, potential


def _body_energy(mass, inertia, r_dot, p, p_dot, gravity, r):
    """(kinetic, gravity potential) of one body."""
    return (body.kinetic_energy(mass, inertia, r_dot, p, p_dot),
            body.gravity_potential(mass, gravity, r))


BODY_ENERGY = traced(_body_energy)  # traced once per argument structure


def energy(ir: ModelIR, x: Coordinates, spring_potential):
    """(kinetic, potential): 1/2 m v.v + 1/2 w_bar^T J_bar w_bar; -m g.r + springs."""
    kinetic, potential = 0.0, spring_potential
    gravity = constant(ir.gravity)
    for k, b in enumerate(ir.bodies):
        body_kinetic, body_potential = BODY_ENERGY(
            b.mass, constant(b.inertia), x.r(k, x.q_dot), x.p(k), x.p(k, x.q_dot), gravity,
            x.r(k))
        kinetic, potential = kinetic + body_kinetic, potential + body_potential
    return kinetic, potential


def reaction(phi, lam, r_j, p_j, about) -> tuple:
    """(force, torque) that the rows phi (with multipliers lam) exert on body j (CM r_j, Euler
    parameters p_j), global, the torque about the point `about`.

    From the lecture: force -Phi_r_j^T lam, body-frame torque about the CM -Pi_bar_j^T lam,
    moved to the point P: T_P = A_j n_bar + (r_j - r_P) x F.
    """
    return _reaction(ca.jacobian(phi, r_j), ca.jacobian(phi, p_j), lam, r_j, p_j, about)


def _reaction(phi_r, phi_p, lam, r_j, p_j, about) -> tuple:
    """reaction's (force, torque) from the rows' Jacobians Phi_r_j, Phi_p_j (equations.mapped.rows
    builds its kernels through reaction, run directly: their C stays as it was)."""
    force = -phi_r.T @ lam
    n_bar = -0.5 * euler.g_matrix(p_j) @ phi_p.T @ lam
    return force, euler.rotation(p_j) @ n_bar + ca.cross(r_j - about, force)


REACTION = traced(_reaction)  # traced once per structure of the Jacobian blocks


def _rows(rows) -> slice | list:
    """A joint's row indices as a slice when consecutive (one cheaper SX slice)."""
    rows = list(rows)
    if rows and rows == list(range(rows[0], rows[-1] + 1)):
        return slice(rows[0], rows[-1] + 1)
    return rows


def reactions(ir: ModelIR, x: Coordinates, phi_with_ground, lam):
    """Force and torque each joint exerts ON body_j: global, torque about body_i's joint point
    (reaction of its rows, plus its motor's and its stop's)."""
    forces, torques = [], []
    for joint in ir.joints:
        rows = _rows(joint.rows)
        b = joint.body_j
        joint_point = x.point(joint.body_i, joint.point_i)
        phi, r_j, p_j = phi_with_ground[rows], x.r(b), x.p(b)
        force, torque = REACTION(ca.jacobian(phi, r_j), ca.jacobian(phi, p_j), lam[rows], r_j,
                                 p_j, joint_point)
        for motor in (m for m in ir.motors if m.name == joint.name):  # its actuation
            motor_force, motor_torque = motors.reaction(motor, x, joint_point)
            force, torque = force + motor_force, torque + motor_torque
        for stop in (s for s in ir.limits if s.name == joint.name):  # its stop
            stop_force, stop_torque = limits.reaction(stop, x, joint_point)
            force, torque = force + stop_force, torque + stop_torque
        forces.append(force)
        torques.append(torque)
    empty = ca.SX(3, 0)
    return (ca.horzcat(*forces) if forces else empty, ca.horzcat(*torques) if torques else empty)
