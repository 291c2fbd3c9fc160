"""The force laws' shared terms: points of frames, the spring-damper-actuator law along a
coordinate, a force at a point, a torque, a force law replaced by an input symbol.

Generalized forces come from virtual work by AD (equations/eom.py): a force F at a point with
global position x(q) contributes x_q^T F; a spring with length l(q) and tension f contributes
-l_q^T f; a torque n_bar (body frame) contributes 2 G^T n_bar. A frame is anything with `r` (the
origin, global) and `A` (its rotation matrix), e.g. elements.primitives.Frame.
"""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca

from casmech.core import euler
from casmech.core.records import record


def at(frame, s_bar):
    """Global position of the point s_bar (body frame) of a frame."""
    return frame.r + frame.A @ s_bar


def distance(fi, fj, s_i, s_j):
    """|point s_j of frame j - point s_i of frame i|: a tsda's length."""
    d = at(fj, s_j) - at(fi, s_i)
    return ca.sqrt(d.T @ d)


def relative_angle(ai, aj, u_i, v_i, u_j):
    """Rotation of body j about a joint axis from the joint frame (body-frame unit vectors
    u_i, v_i on body i, u_j on body j; rotations ai, aj): atan2(v_i.u_j, u_i.u_j)."""
    u_j, v_i, u_i = aj @ u_j, ai @ v_i, ai @ u_i
    return ca.atan2(v_i.T @ u_j, u_i.T @ u_j)


@record
class SpringKind:
    """A spring-damper-actuator element type: the coordinate it acts along, of its two frames
    and its vectors; the vectors' keys (in ForceIR.points | ForceIR.axes); the parameter of the
    coordinate's rest value; the names under which its actuator reads the coordinate and its
    rate."""

    coordinate: Callable
    vectors: tuple[str, ...]
    rest: str
    names: tuple[str, str]

    def parameters(self, force) -> tuple:
        """(stiffness, damping, rest value) of an element."""
        return tuple(force.params[k] for k in ("stiffness", "damping", self.rest))

    def vector_values(self, geometry) -> list:
        """The vectors of an element (or of a joint: rsda_angle)."""
        return [geometry.axes[k] if k in geometry.axes else geometry.points[k]
                for k in self.vectors]


def spring_law(value, value_dot, t, k, c, rest, actuator, names: tuple[str, str],
               states=None) -> tuple:
    """(tension, potential) of a spring-damper-actuator along a coordinate and its rate;
    `states`: the further state values the actuator reads (equations.coordinates)."""
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


def in_global(frame_name: str, rotation, vector):
    """A force or torque vector given in frame_name ("body": body i's, else global) in the
    global frame."""
    return rotation @ vector if frame_name == "body" else vector


def point_force(frame, s_bar, q, force):
    """The generalized force over q of a global force at the point s_bar of a frame."""
    return ca.jacobian(at(frame, s_bar), q).T @ force


def torque(frame, p, torque_vector):
    """Q_p = 2 G(p)^T n_bar of a global torque on the body of frame (Euler parameters p;
    n_bar = A^T torque, body frame)."""
    return 2 * euler.g_matrix(p).T @ (frame.A.T @ torque_vector)


class Input:
    """A force law that is one input symbol (the ScalarFunction interface force laws call):
    runtime/linearize.py replaces an element's law by inputs through its entry's
    `with_inputs`."""

    states: dict = {}

    def __init__(self, symbol):
        self.symbol = symbol

    def casadi(self, **_):
        return self.symbol
