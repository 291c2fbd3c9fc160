"""The DAE residual and the kinematic constraints the collocation imposes, on the interpreted
(SX, from the parametric system) or the compiled functions (backends.compile(model, mode):
C externals with first derivatives, so IPOPT runs with a limited-memory Hessian).

    residual(t, x, z, u) -> (ode, alg)          the index-1 DAE of dae.py
    kinematics(t, x) -> (phi, phi_q, nu)        over the DAE's independent rows
"""

from __future__ import annotations

import casadi as ca

from casmech import backends
from casmech.backends import codegen
from casmech.core.records import record
from casmech.optimal.dae import DAE
from casmech.schema.resolved import ResolvedModel


@record
class Residuals:
    residual: ca.Function
    kinematics: ca.Function
    mode: str  # the mode the functions come from: interpreted | compiled


def _interpreted(dae: DAE) -> Residuals:
    theta, rows = ca.DM.zeros(dae.theta.numel()), list(dae.rows)
    q = dae.x[:dae.n]
    system = dae.system
    kinematics = ca.Function("kinematics", [dae.t, dae.x], [
        system["phi"](dae.t, q, theta)[rows], system["phi_q"](dae.t, q, theta)[rows, :],
        system["nu"](dae.t, q, theta)[rows]])
    residual = ca.Function("f", [dae.t, dae.x, dae.z, dae.u], [
        ca.substitute(dae.ode, dae.theta, theta), ca.substitute(dae.alg, dae.theta, theta)])
    return Residuals(residual, kinematics, "interpreted")


def _compiled(dae: DAE, functions, controls: ca.Function) -> Residuals:
    n, rows = dae.n, list(dae.rows)
    t, x = ca.MX.sym("t"), ca.MX.sym("x", 2 * n)
    z, u = ca.MX.sym("z", dae.z.numel()), ca.MX.sym("u", dae.u.numel())
    q, q_dot, q_ddot, lam = x[:n], x[n:], z[:n], z[n:]
    phi_q = functions["phi_q"](t, q)[rows, :]
    forces = functions["generalized_forces"](t, q, q_dot) + controls(q, u)
    alg = ca.vertcat(functions["mass_matrix"](q) @ q_ddot + phi_q.T @ lam - forces,
                     phi_q @ q_ddot - functions["gamma"](t, q, q_dot)[rows])
    residual = ca.Function("f", [t, x, z, u], [ca.vertcat(q_dot, q_ddot), alg])
    kinematics = ca.Function("kinematics", [t, x], [
        functions["phi"](t, q)[rows], phi_q, functions["nu"](t, q)[rows]])
    return Residuals(residual, kinematics, "compiled")


def residuals(model: ResolvedModel, dae: DAE, controls: ca.Function,
              mode: str = "interpreted") -> Residuals:
    """`mode` as backends.compile takes it (interpreted | compiled | auto)."""
    if mode == "interpreted":
        return _interpreted(dae)
    functions = backends.compile(model, mode)
    if codegen.mode_of(functions) == "interpreted":
        return _interpreted(dae)
    return _compiled(dae, functions, controls)
