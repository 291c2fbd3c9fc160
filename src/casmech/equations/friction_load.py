"""The load of a joint friction with a part proportional to it (`mu`, `mu_static`;
docs/forces.md#joint-friction): the joint's reaction normal to its motion,

    L = |F - (F . w) w|            along a displacement (translational, cylindrical),
    L = radius |F - (F . w) w|     along an angle (revolute: the radial force on the bearing),

F the force the joint's rows exert on body_j, w its axis. Stuck, F is the rows' (the holding
row's multiplier is along w or about it, so L is the other rows'), a function of the
multipliers (`normal`). Sliding, the friction force f = a - d mu L (a = -d Tc - c s_dot, d the
mode) changes the motion and so L: with z0 = (q_ddot, lam) of the model without the load part
and z1 the response to a unit generalized force along the coordinate (both from one solve of
the r-p system [M Phi_q^T; Phi_q 0] z = [Q; gamma]), F = F0 - d g F1 with g = mu L, and

    g^2 = mu^2 |n0 - d g n1|^2   (n = the normal part of F, times radius along an angle),

a quadratic in g >= 0 with one such root while mu |n1| < 1 (`sliding`, exact). Beyond it the
friction would lock the joint on its own (Painleve's paradox), which the run reports.
"""

from __future__ import annotations

import casadi as ca

from casmech.core.values import constant
from casmech.equations import friction
from casmech.equations.symbols import Coordinates


def _axis(element, x: Coordinates):
    return x.frame(element.body_i).A @ constant(element.axes["w_i"])


def _normal(element, x: Coordinates, force):
    """The load's vector of a reaction force: its part normal to the axis (times radius along
    an angle)."""
    w = _axis(element, x)
    arm = element.params["radius"] if friction.COORDINATE[element.type] == "angle" else 1.0
    return arm * (force - w * ca.dot(force, w))


def _column(functions, element) -> int:
    return [j.name for j in functions.ir.joints].index(element.name)


def normal(functions, element) -> ca.Function:
    """(t, q, q_dot, lam) -> L, the load of `element`'s joint in the model of `functions`."""
    x = Coordinates.create(functions.ir.n_bodies)
    lam = ca.SX.sym("lam", functions.n_rows)
    force = functions["reactions"](x.t, x.q, x.q_dot, lam)[0][:, _column(functions, element)]
    value = x.ground_fixed(ca.norm_2(_normal(element, x, force)))
    return ca.Function("friction_load", [x.t, x.q, x.q_dot, lam], [value])


def sliding(functions, element, direction: float) -> ca.Function:
    """(t, q, q_dot) -> (g = mu L, mu |n1|) while `element` slides in `direction`, in the
    model of `functions` (the friction's load part absent from it; module docstring)."""
    x = Coordinates.create(functions.ir.n_bodies)
    t, q, q_dot = x.t, x.q, x.q_dot
    mass = functions["mass_matrix"](q)
    jacobian = functions["phi_q"](t, q)
    n, m = mass.shape[0], jacobian.shape[0]
    unit = x.ground_fixed(ca.jacobian(friction.coordinate(element, x), q)).T
    system = ca.blockcat([[mass, jacobian.T], [jacobian, ca.SX(m, m)]])
    rhs = ca.horzcat(ca.vertcat(functions["generalized_forces"](t, q, q_dot),
                                functions["gamma"](t, q, q_dot)), ca.vertcat(unit, ca.SX(m, 1)))
    z = ca.solve(system, rhs)
    column = _column(functions, element)
    base = functions["reactions"](t, q, q_dot, z[n:, 0])[0][:, column]
    moved = functions["reactions"](t, q, q_dot, z[n:, 0] + z[n:, 1])[0][:, column]
    n0, n1 = _normal(element, x, base), _normal(element, x, moved - base)
    mu, d = element.params["mu"], direction
    a = 1 - mu ** 2 * ca.dot(n1, n1)
    b = 2 * d * mu ** 2 * ca.dot(n0, n1)
    c = -mu ** 2 * ca.dot(n0, n0)
    # the root >= 0 of a g^2 + b g + c = 0 (c <= 0 < a), written without cancellation
    root = b + ca.sqrt(ca.fmax(b * b - 4 * a * c, 0))
    g = ca.if_else(c == 0, 0, -2 * c / ca.if_else(root == 0, 1, root))
    outputs = x.ground_fixed(ca.vertcat(g, mu * ca.norm_2(n1)))
    return ca.Function("friction_sliding_load", [t, q, q_dot], [outputs])
