"""Equations of motion in the r-p form, forces, energy and joint reactions.

r-p form (Haug 1989, ch. 11): M r_ddot + Phi_r^T lam = F and
4 G^T J_bar G p_ddot + Phi_p^T lam + P^T lam_P = 2 G^T n_bar + 8 G_dot^T J_bar G_dot p.
Generalized forces of force elements come from virtual work by AD: a force F at a point with
global position x(q) contributes x_q^T F; a spring with length l(q) and tension f contributes
-l_q^T f; a torque n_bar (body frame) contributes 2 G^T n_bar.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca

from casmech.compiler import body, bushing, contact, coordinates, limits, motors
from casmech.compiler.assemble import Coordinates
from casmech.compiler.ir import ForceIR, ModelIR, constant
from casmech.compiler.primitives import Frame
from casmech.geometry import euler


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


def at(frame: Frame, s_bar):
    """Global position of the point s_bar (body frame) of a frame."""
    return frame.r + frame.A @ s_bar


def point(x: Coordinates, k: int, s_bar):
    """Global position of a body-fixed point (ground: s_bar is already global)."""
    return at(x.frame(k), constant(s_bar))


def rate(expr, x: Coordinates):
    return ca.jacobian(expr, x.q) @ x.q_dot


def distance(fi: Frame, fj: Frame, s_i, s_j):
    """|point s_j of frame j - point s_i of frame i|: a tsda's length."""
    d = at(fj, s_j) - at(fi, s_i)
    return ca.sqrt(d.T @ d)


def relative_angle(ai, aj, u_i, v_i, u_j):
    """Rotation of body j about a joint axis from the joint frame (body-frame unit vectors
    u_i, v_i on body i, u_j on body j; rotations ai, aj): atan2(v_i.u_j, u_i.u_j)."""
    u_j, v_i, u_i = aj @ u_j, ai @ v_i, ai @ u_i
    return ca.atan2(v_i.T @ u_j, u_i.T @ u_j)


@dataclass(frozen=True)
class SpringKind:
    """A spring-damper-actuator element type: the coordinate it acts along, of its two frames
    and its vectors; the vectors' keys (in ForceIR.points | ForceIR.axes); the parameter of the
    coordinate's rest value; the names under which its actuator reads the coordinate and its
    rate."""

    coordinate: Callable
    vectors: tuple[str, ...]
    rest: str
    names: tuple[str, str]

    def parameters(self, force: ForceIR) -> tuple:
        """(stiffness, damping, rest value) of an element."""
        return tuple(force.params[k] for k in ("stiffness", "damping", self.rest))

    def vector_values(self, geometry) -> list:
        """The vectors of an element (or of a joint: rsda_angle)."""
        return [geometry.axes[k] if k in geometry.axes else geometry.points[k]
                for k in self.vectors]


SPRINGS = {
    "tsda": SpringKind(distance, ("s_i", "s_j"), "free_length", ("length", "length_dot")),
    "rsda": SpringKind(lambda fi, fj, *axes: relative_angle(fi.A, fj.A, *axes),
                       ("u_i", "v_i", "u_j"), "free_angle", ("angle", "angle_dot")),
}


def rsda_angle(geometry, x: Coordinates):
    """Rotation of body j about the joint axis (relative_angle) of an rsda or a joint."""
    return _coordinate(SPRINGS["rsda"], geometry, x)


def _coordinate(kind: SpringKind, geometry, x: Coordinates):
    return kind.coordinate(x.frame(geometry.body_i), x.frame(geometry.body_j),
                           *(constant(v) for v in kind.vector_values(geometry)))


def spring_law(value, value_dot, t, k, c, rest, actuator, names: tuple[str, str],
               states=None) -> tuple:
    """(tension, potential) of a spring-damper-actuator along a coordinate and its rate;
    `states`: the further state values the actuator reads (compiler.coordinates)."""
    tension = k * (value - rest) + c * value_dot
    if actuator is not None:
        tension += actuator.casadi(t=t, **{names[0]: value, names[1]: value_dot},
                                   **(states or {}))
    return tension, 0.5 * k * (value - rest) ** 2


def spring(kind: SpringKind, coordinate, motion: tuple, parameters, actuator, states=None
           ) -> tuple:
    """(generalized force over q, potential) of a spring-damper-actuator of a kind acting
    along `coordinate`(q), motion = (q, q_dot, t), parameters = (stiffness, damping, rest)
    (spring_law at the coordinate's rate along q_dot)."""
    q, q_dot, t = motion
    coordinate_q = ca.jacobian(coordinate, q)
    tension, potential = spring_law(coordinate, coordinate_q @ q_dot, t, *parameters, actuator,
                                    kind.names, states)
    return -coordinate_q.T * tension, potential


def _spring(force: ForceIR, x: Coordinates):
    """(generalized force, potential) of a tsda or rsda."""
    states = coordinates.values(force.actuator, x) if force.actuator is not None else None
    kind = SPRINGS[force.type]
    return spring(kind, _coordinate(kind, force, x), (x.q, x.q_dot, x.t), kind.parameters(force),
                  force.actuator, states)


def in_global(frame_name: str, rotation, vector):
    """A force or torque vector given in frame_name ("body": body i's, else global) in the
    global frame."""
    return rotation @ vector if frame_name == "body" else vector


def _value(force: ForceIR, x: Coordinates):
    """The force/torque vector in the global frame."""
    v = ca.vertcat(*[component.casadi(t=x.t, **coordinates.values(component, x))
                     for component in force.value])
    return in_global(force.frame, x.frame(force.body_i).A, v)


def point_force(frame: Frame, s_bar, q, force):
    """The generalized force over q of a global force at the point s_bar of a frame."""
    return ca.jacobian(at(frame, s_bar), q).T @ force


def torque(frame: Frame, p, torque_vector):
    """Q_p of a global torque on the body of frame (Euler parameters p)."""
    return body.generalized_torque(p, frame.A.T @ torque_vector)


def _point_force(force, x):
    s_bar = constant(force.points.get("s", [0.0, 0.0, 0.0]))
    return point_force(x.frame(force.body_i), s_bar, x.q, _value(force, x)), 0.0


def _torque(force, x):
    k = force.body_i
    generalized = ca.SX.zeros(x.q.numel(), 1)
    start = 3 * x.n_bodies + 4 * k
    generalized[start:start + 4] = torque(x.frame(k), x.p(k), _value(force, x))
    return generalized, 0.0


FORCE_ELEMENTS: dict[str, Callable] = {
    **dict.fromkeys(SPRINGS, _spring),  # tsda, rsda
    "force": _point_force,
    "torque": _torque,
    "bushing": lambda force, x: bushing.generalized_force(force, x),
    # (lambdas: compiler.contact and compiler.limits import this module through coordinates)
    "sphere_plane": lambda force, x: contact.generalized_force(force, x),
    "sphere_sphere": lambda force, x: contact.generalized_force(force, x),
    "points_plane": lambda force, x: contact.generalized_force(force, x),
    "capsule_plane": lambda force, x: contact.generalized_force(force, x),
    "limit_angle": lambda force, x: limits.generalized_force(force, x),  # stops (ir.limits)
    "limit_displacement": lambda force, x: limits.generalized_force(force, x),
}
FORCE_ELEMENTS.update(motors.FORCE_ELEMENTS)  # effort motors of joints (ir.motors)


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


def energy(ir: ModelIR, x: Coordinates, spring_potential):
    """(kinetic, potential): 1/2 m v.v + 1/2 w_bar^T J_bar w_bar; -m g.r + springs."""
    kinetic, potential = 0.0, spring_potential
    for k, b in enumerate(ir.bodies):
        kinetic += body.kinetic_energy(b.mass, constant(b.inertia), x.r(k, x.q_dot), x.p(k),
                                       x.p(k, x.q_dot))
        potential += body.gravity_potential(b.mass, constant(ir.gravity), x.r(k))
    return kinetic, potential


def reaction(phi, lam, r_j, p_j, about) -> tuple:
    """(force, torque) that the rows phi (with multipliers lam) exert on body j (CM r_j, Euler
    parameters p_j), global, the torque about the point `about`.

    From the lecture: force -Phi_r_j^T lam, body-frame torque about the CM -Pi_bar_j^T lam,
    moved to the point P: T_P = A_j n_bar + (r_j - r_P) x F.
    """
    force = -ca.jacobian(phi, r_j).T @ lam
    n_bar = -0.5 * euler.g_matrix(p_j) @ ca.jacobian(phi, p_j).T @ lam
    return force, euler.rotation(p_j) @ n_bar + ca.cross(r_j - about, force)


def reactions(ir: ModelIR, x: Coordinates, phi_with_ground, lam):
    """Force and torque each joint exerts ON body_j: global, torque about body_i's joint point
    (reaction of its rows, plus its motor's and its stop's)."""
    forces, torques = [], []
    for joint in ir.joints:
        rows = list(joint.rows)
        b = joint.body_j
        joint_point = point(x, joint.body_i, joint.point_i)
        force, torque = reaction(phi_with_ground[rows], lam[rows], x.r(b), x.p(b), joint_point)
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
