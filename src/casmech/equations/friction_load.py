"""The load of a joint friction with a part proportional to it (`mu`, `mu_static`;
docs/forces.md#joint-friction): the joint's reaction normal to its motion,

    L = |F - (F . w) w|            along a displacement (translational, cylindrical),
    L = radius |F - (F . w) w|     along an angle (revolute: the radial force on the bearing),

F the force the joint's rows exert on body_j, w its axis. Stuck, F is the rows' (the holding
row's multiplier is along w or about it, so L is the other rows'), a function of the
multipliers (`normal`). Sliding, the friction force f = a - d mu L (a = -d Tc - c s_dot, d the
mode) changes the motion and so L: with lam0 the multipliers of the model without the load
part and lam1 their response to a unit generalized force along the coordinate (both from one
solve of the Newton-Euler form's Schur complement: `sliding`), F = F0 - d g F1 with g = mu L,
and

    g^2 = mu^2 |n0 - d g n1|^2   (n = the normal part of F, times radius along an angle),

a quadratic in g >= 0 with one such root while mu |n1| < 1 (`sliding`, exact). Beyond it the
friction would lock the joint on its own (Painleve's paradox), which the run reports.
"""

from __future__ import annotations

import casadi as ca

from casmech.core import euler
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


def _velocities(x: Coordinates, n_bodies: int):
    """v = [r_dot; omega_bar] of (q, q_dot): omega_bar_k = 2 G(p_k) p_dot_k."""
    omega = [2 * euler.g_matrix(x.p(k)) @ x.p(k, x.q_dot) for k in range(n_bodies)]
    return ca.vertcat(x.q_dot[:3 * n_bodies], *omega)


def sliding(functions, element, direction: float) -> ca.Function:
    """(t, q, q_dot) -> (g = mu L, mu |n1|) while `element` slides in `direction`, in the
    model of `functions` (the friction's load part absent from it; module docstring). The
    multipliers are the Newton-Euler form's: (P M^-1 P^T) lam = P M^-1 F - gamma with
    M = blkdiag(m I, J_bar) (constant), over the joint rows only, the smallest system whose
    multipliers are the joints' reactions."""
    nb = functions.ir.n_bodies
    x = Coordinates.create(nb)
    t, q, q_dot = x.t, x.q, x.q_dot
    v = _velocities(x, nb)
    inverse = ca.inv(ca.DM(functions["romega_mass"](ca.DM.zeros(7 * nb))))
    jacobian = functions["romega_jacobian"](t, q)
    m = jacobian.shape[0]
    # a unit generalized force along the coordinate, in v: (dq_dot/dv)^T s_q^T
    v_sym = ca.SX.sym("v", 6 * nb)
    q_dot_of_v = functions["romega_q_dot"](q, v_sym)
    unit = ca.substitute(ca.jacobian(q_dot_of_v, v_sym), v_sym, v).T @ x.ground_fixed(
        ca.jacobian(friction.coordinate(element, x), q)).T
    schur = jacobian @ inverse @ jacobian.T
    rhs = ca.horzcat(jacobian @ inverse @ functions["romega_forces"](t, q, v)
                     - functions["romega_gamma"](t, q, v), jacobian @ inverse @ unit)
    z = ca.solve(schur, rhs)
    rows = functions.n_rows - m  # the bodies' normalization rows, after the joint rows: 0
    lam0, lam1 = ca.vertcat(z[:, 0], ca.SX(rows, 1)), ca.vertcat(z[:, 1], ca.SX(rows, 1))
    column = _column(functions, element)
    base = functions["reactions"](t, q, q_dot, lam0)[0][:, column]
    moved = functions["reactions"](t, q, q_dot, lam0 + lam1)[0][:, column]
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
