"""The r-omega (Newton-Euler) form of the equations of motion (Haug 1989, ch. 11; ME751).

State: q = [r (3 nb); p (4 nb)] and v = [r_dot (3 nb); omega_bar (3 nb)] (body-frame angular
velocities, same block layout as q). Per body k:
    m_k r_ddot_k + Phi_r_k^T lam = F_k
    J_bar_k omega_bar_dot_k + Pi_bar_k^T lam = n_bar_k - omega_bar_k~ J_bar_k omega_bar_k
    p_dot_k = 1/2 G(p_k)^T omega_bar_k
lam holds the multipliers of the JOINT rows only: |p| = 1 is kept by the kinematic equation, so
the normalization rows of the r-p model are not constraints here. Velocity constraint
[Phi_r, Pi_bar] v = nu; acceleration constraint [Phi_r, Pi_bar] v_dot = gamma_hat, with gamma_hat
the negated total time derivative (by AD) of c(t, q, v) = [Phi_r, Pi_bar] v - nu along
q_dot(q, v). Applied forces are the r-p ones (eom.applied_forces) at q_dot(q, v); the body torque
is n_bar = 1/2 G Q_p (virtual work with delta p = 1/2 G^T delta pi_bar).
"""

from __future__ import annotations

import casadi as ca

from casmech.core.values import constant
from casmech.equations import body, eom
from casmech.equations.assemble import ConstraintSystem, Coordinates
from casmech.model.ir import ModelIR


def omega_bar(x: Coordinates, v, k: int):
    """omega_bar of body k in v = [r_dot; omega_bar]."""
    start = 3 * x.n_bodies + 3 * k
    return v[start:start + 3]


def q_dot_of(x: Coordinates, v):
    """q_dot(q, v) = [r_dot; 1/2 G(p_k)^T omega_bar_k ...]."""
    nb = x.n_bodies
    p_dot = [body.p_dot(x.p(k), omega_bar(x, v, k)) for k in range(nb)]
    return ca.vertcat(v[:3 * nb], *p_dot)


def q_ddot(q_dot, q, v, v_dot):
    """The time derivative of q_dot(q, v) (e.g. q_dot_of, or one body's p_dot)."""
    return ca.jacobian(q_dot, q) @ q_dot + ca.jacobian(q_dot, v) @ v_dot


def gamma_hat(jacobian, nu, v, q, q_dot, t):
    """-d/dt (jacobian v - nu) along q_dot(q, v) at constant v: the acceleration constraint's
    right-hand side (rows of [Phi_r, Pi_bar] over q and t)."""
    c = jacobian @ v - nu
    return -(ca.jacobian(c, q) @ q_dot + ca.jacobian(c, t))


def body_torque(p, q_p, w, inertia):
    """n_bar - omega_bar~ J_bar omega_bar of one body, n_bar = 1/2 G Q_p."""
    return body.moment(p, q_p) - body.gyroscopic(w, inertia)


def mass(ir: ModelIR):
    """blkdiag(m_k I_3 ..., J_bar_k ...) (6 nb x 6 nb, v layout)."""
    blocks = [b.mass * ca.DM.eye(3) for b in ir.bodies] + [constant(b.inertia) for b in ir.bodies]
    return ca.SX(ca.diagcat(*blocks)) if blocks else ca.SX(0, 0)


def forces(ir: ModelIR, x: Coordinates, v, q_dot):
    """[F; n_bar - omega_bar~ J_bar omega_bar] from the r-p applied forces at q_dot(q, v)."""
    nb = ir.n_bodies
    applied = ca.substitute(eom.applied_forces(ir, x)[0], x.q_dot, q_dot)
    torques = []
    for k, b in enumerate(ir.bodies):
        q_p = applied[3 * nb + 4 * k:3 * nb + 4 * k + 4]
        torques.append(body_torque(x.p(k), q_p, omega_bar(x, v, k), constant(b.inertia)))
    return ca.vertcat(applied[:3 * nb], *torques)


def definitions(ir: ModelIR, cs: ConstraintSystem) -> list[tuple[str, dict, dict]]:
    """(name, inputs, outputs) of the romega_* functions; ground is substituted in every output."""
    x, n = cs.x, len(ir.primitives)
    t, q = x.t, x.q
    v, v_dot = ca.SX.sym("v", 6 * ir.n_bodies), ca.SX.sym("v_dot", 6 * ir.n_bodies)
    q_dot = q_dot_of(x, v)
    jacobian = ca.horzcat(cs.phi_r, cs.pi_bar)[:n, :]
    nu = cs.nu[:n, :]
    gamma = gamma_hat(jacobian, nu, v, q, q_dot, t)
    fixed = x.ground_fixed
    return [
        ("romega_mass", {"q": q}, {"mass": mass(ir)}),
        ("romega_forces", {"t": t, "q": q, "v": v}, {"forces": fixed(forces(ir, x, v, q_dot))}),
        ("romega_jacobian", {"t": t, "q": q}, {"jacobian": jacobian}),
        ("romega_nu", {"t": t, "q": q}, {"nu": nu}),
        ("romega_gamma", {"t": t, "q": q, "v": v}, {"gamma": gamma}),
        ("romega_q_dot", {"q": q, "v": v}, {"q_dot": q_dot}),
        ("romega_to_rp", {"q": q, "v": v, "v_dot": v_dot},
         {"q_dot": q_dot, "q_ddot": q_ddot(q_dot, q, v, v_dot)}),
    ]
