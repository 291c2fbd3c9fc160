"""The load of a joint friction with a part proportional to it (`mu`, `mu_static`;
docs/forces.md#joint-friction): the joint's reaction normal to its motion,

    L = |F - (F . w) w|            along a displacement (translational, cylindrical),
    L = radius |F - (F . w) w|     along an angle (revolute: the radial force on the bearing),

F the force the joint's rows exert on body_j, w its axis. Stuck, F is the rows' (the holding
row's multiplier is along w or about it, so L is the other rows'), a function of the
multipliers (`normal`). Sliding, the friction force f = a - d mu L (a = -d Tc - c s_dot, d the
mode) changes the motion and so L: with lam0 the multipliers of the model without the load
parts and lam1_j their response to a unit generalized force along joint j's coordinate (one
solve of the Newton-Euler form's Schur complement: `_responses`), F_i = F0_i - sum_j d_j g_j
F1_ij with g_j = mu_j L_j, and

    g_i = mu_i |n0_i - sum_j d_j g_j n1_ij|   (n = the normal part of F, times radius along an
                                               angle),

for one joint a quadratic in g >= 0 with one such root while mu |n1| < 1 (exact), for several
a small system solved by Newton's method from those roots (`sliding`). Beyond a spectral
radius of 1 of mu_i |n1_ij| the frictions could lock the joints on their own (Painleve's
paradox), which the run reports.
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


def load_vector(functions, element, x: Coordinates, lam):
    """The load's vector of `element`'s joint reaction for the multipliers lam (an
    expression of x and lam, linear in lam): |load_vector| is its load L."""
    force = functions["reactions"](x.t, x.q, x.q_dot, lam)[0][:, _column(functions, element)]
    return _normal(element, x, force)


def normal(functions, element) -> ca.Function:
    """(t, q, q_dot, lam) -> L, the load of `element`'s joint in the model of `functions`."""
    x = Coordinates.create(functions.ir.n_bodies)
    lam = ca.SX.sym("lam", functions.n_rows)
    value = x.ground_fixed(ca.norm_2(load_vector(functions, element, x, lam)))
    return ca.Function("friction_load", [x.t, x.q, x.q_dot, lam], [value])


def _velocities(x: Coordinates, n_bodies: int):
    """v = [r_dot; omega_bar] of (q, q_dot): omega_bar_k = 2 G(p_k) p_dot_k."""
    omega = [2 * euler.g_matrix(x.p(k)) @ x.p(k, x.q_dot) for k in range(n_bodies)]
    return ca.vertcat(x.q_dot[:3 * n_bodies], *omega)


NEWTON_STEPS = 16  # Newton steps on several joints' loads, seeded by their one-joint roots


def _responses(functions, elements):
    """(x, n0, n1): the load vectors n0_i of the joints' reactions in the model without the
    load parts and n1[i][j], joint i's per unit generalized force along joint j's coordinate.
    The multipliers are the Newton-Euler form's: (P M^-1 P^T) lam = P M^-1 F - gamma with
    M = blkdiag(m I, J_bar) (constant), over the joint rows only, the smallest system whose
    multipliers are the joints' reactions; one solve gives every column."""
    nb = functions.ir.n_bodies
    x = Coordinates.create(nb)
    t, q = x.t, x.q
    v = _velocities(x, nb)
    inverse = ca.inv(ca.DM(functions["romega_mass"](ca.DM.zeros(7 * nb))))
    jacobian = functions["romega_jacobian"](t, q)
    m = jacobian.shape[0]
    # a unit generalized force along each coordinate, in v: (dq_dot/dv)^T s_q^T
    v_sym = ca.SX.sym("v", 6 * nb)
    q_dot_of_v = ca.substitute(ca.jacobian(functions["romega_q_dot"](q, v_sym), v_sym), v_sym, v)
    units = [q_dot_of_v.T @ x.ground_fixed(ca.jacobian(friction.coordinate(e, x), q)).T
             for e in elements]
    rhs = ca.horzcat(jacobian @ inverse @ functions["romega_forces"](t, q, v)
                     - functions["romega_gamma"](t, q, v), *(jacobian @ inverse @ u for u in units))
    z = ca.solve(jacobian @ inverse @ jacobian.T, rhs)
    rows = ca.SX(functions.n_rows - m, 1)  # the bodies' normalization rows, after the joints'
    lam0, lam1 = ca.vertcat(z[:, 0], rows), [ca.vertcat(z[:, 1 + j], rows)
                                             for j in range(len(elements))]
    n0 = [load_vector(functions, e, x, lam0) for e in elements]
    n1 = [[load_vector(functions, e, x, u) for u in lam1] for e in elements]
    return x, n0, n1


def _one(mu, d, n0, n1):
    """The root g >= 0 of g^2 = mu^2 |n0 - d g n1|^2 (one joint; c <= 0 < a), written without
    cancellation."""
    a = 1 - mu ** 2 * ca.dot(n1, n1)
    b = 2 * d * mu ** 2 * ca.dot(n0, n1)
    c = -mu ** 2 * ca.dot(n0, n0)
    root = b + ca.sqrt(ca.fmax(b * b - 4 * a * c, 0))
    return ca.if_else(c == 0, 0, -2 * c / ca.if_else(root == 0, 1, root))


def _length(vector):
    """|vector|, its derivative 0 (not 0/0) where the vector is 0: an unloaded joint's load
    part stays 0 and Newton's steps stay finite."""
    square = ca.dot(vector, vector)
    return (square != 0) * ca.sqrt(ca.if_else(square == 0, 1, square))


def coupled(mu, d, n0, n1):
    """(g, checked): the load parts g_i = mu_i |n0_i - sum_j d_j g_j n1_ij| (`sliding`) as
    expressions of the given ones (d_j numbers or expressions), one joint's the quadratic's
    root (`_one`, exact), several by NEWTON_STEPS of Newton's method from those roots; and
    what runtime/load_checks.py reads of them: [g; the largest residual; A_ij = mu_i |n1_ij|
    row by row]."""
    k = len(mu)
    seed = ca.vertcat(*(_one(mu[i], d[i], n0[i], n1[i][i]) for i in range(k)))
    g = ca.SX.sym("g", k)
    d_s = ca.SX.sym("d", k)
    n0_s = [ca.SX.sym(f"n0_{i}", 3) for i in range(k)]
    n1_s = [[ca.SX.sym(f"n1_{i}_{j}", 3) for j in range(k)] for i in range(k)]
    residual = g - ca.vertcat(*(mu[i] * _length(n0_s[i] - sum(
        d_s[j] * g[j] * n1_s[i][j] for j in range(k))) for i in range(k)))
    given = [d_s, *n0_s, *(v for row in n1_s for v in row)]
    values = [ca.vertcat(*d), *n0, *(v for row in n1 for v in row)]
    left = ca.Function("friction_load_residual", [g, *given], [residual])
    step = ca.Function("friction_load_newton", [g, *given],
                       [g - ca.solve(ca.jacobian(residual, g), residual)])
    solved = seed
    for _ in range(NEWTON_STEPS if k > 1 else 0):
        solved = step(solved, *values)
    ratios = [mu[i] * ca.norm_2(n1[i][j]) for i in range(k) for j in range(k)]
    return solved, ca.vertcat(solved, ca.mmax(ca.fabs(left(solved, *values))), *ratios)


def sliding(functions, elements, directions) -> ca.Function:
    """(t, q, q_dot) -> (g_1..g_k, residual, A) while the joints `elements` slide in
    `directions`, in the model of `functions` (the load parts absent from it; module
    docstring): g_i = mu_i L_i their friction forces' load parts, the system's largest
    residual |g_i - mu_i |n_i(g)|| at the returned g, and A_ij = mu_i |n1_ij| (the change of
    joint i's load part per unit friction force along j), row by row.

    With n_i(g) = n0_i - sum_j d_j g_j n1_ij affine in g, the loads solve g_i = mu_i |n_i(g)|:
    one joint's is the quadratic's root (`_one`, exact); several are coupled, solved by
    Newton's method from the one-joint roots (CasADi differentiates the residual). While A's
    spectral radius is below 1 the map g -> mu |n(g)| is a contraction (in a weighted max
    norm), so the loads are unique; at 1 or above the frictions could lock the joints on
    their own (Painleve's paradox), which the run reports."""
    x, n0, n1 = _responses(functions, elements)
    _, checked = coupled([e.params["mu"] for e in elements],
                         [float(value) for value in directions], n0, n1)
    return ca.Function("friction_sliding_load", [x.t, x.q, x.q_dot], [x.ground_fixed(checked)])


def part(system: ca.Function, index: int) -> ca.Function:
    """(t, q, q_dot) -> (g_index, ...): one joint's load part of a `sliding` system, the form
    its law reads (equations/friction.py)."""
    t, q, q_dot = (ca.SX.sym(n, *system.size_in(i)) for i, n in enumerate(("t", "q", "q_dot")))
    return ca.Function("friction_load_part", [t, q, q_dot], [system(t, q, q_dot)[index]])
