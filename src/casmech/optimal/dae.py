"""The index-1 DAE of a parametric system, its consistent initial state and its outputs.

    x = [q, q_dot]    z = [q_ddot, lam]    p = [theta, u]
    ode: [q_dot; q_ddot]
    alg: [M q_ddot + Phi_q^T lam - Q - B^T u;  Phi_q q_ddot - gamma]

over the independent constraint rows at the assembled pose (redundant rows dropped): the rp
formulation's index-1 residual (formulations.protocol, stabilization "projection") over the
system's bundle with d = d(theta), its rows unscaled (s = 1) and the redundant ones masked
(w = 1) with their multipliers 0 and their equations left out, plus the controls' forces.
The initial state is a function of theta: positions are casmech's assembly, the point of Phi =
0 closest to the file's pose (itself a function of theta), by the rootfinder of
numerics.kkt.closest_point that the runtime's assembly ends with, so its derivative is the
implicit one; velocities are the file's velocities corrected by the least-squares step onto
Phi_q q_dot = nu."""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.equations.checks import structure
from casmech.formulations.registry import FORMULATIONS
from casmech.numerics import kkt
from casmech.optimal.system import ParametricSystem
from casmech.runtime.assembly import initial_state
from casmech.runtime.results import column_names

FORMULATION = "rp"  # the registered formulation whose residual the DAE is (body coordinates)


@record
class DAE:
    """Symbols and residuals of the index-1 DAE (SX), with the rows it keeps."""

    system: ParametricSystem
    rows: tuple[int, ...]  # independent constraint rows
    t: ca.SX
    x: ca.SX
    z: ca.SX
    theta: ca.SX
    u: ca.SX
    ode: ca.SX
    alg: ca.SX
    t0: float
    q_assembled: np.ndarray
    q_dot_assembled: np.ndarray

    @property
    def n(self) -> int:
        return self.system.n_coordinates

    @property
    def p(self) -> ca.SX:
        return ca.vertcat(self.theta, self.u)

    def problem(self) -> dict:
        return {"t": self.t, "x": self.x, "z": self.z, "p": self.p, "ode": self.ode,
                "alg": self.alg}

    def split(self, x, z):
        n = self.n
        return x[:n], x[n:], z[:n], z[n:]

    def full_multipliers(self, lam_rows):
        """lam over every row of phi (zeros on the dropped redundant rows)."""
        m = self.system.nominal.n_rows
        lam = ca.MX.zeros(m, lam_rows.shape[1]) if isinstance(lam_rows, ca.MX) else \
            ca.SX.zeros(m, lam_rows.shape[1])
        for k, row in enumerate(self.rows):
            lam[row, :] = lam_rows[k, :]
        return lam


def build_dae(system: ParametricSystem, controls: ca.Function | None = None,
              t0: float = 0.0) -> DAE:
    """The DAE; `controls(q, u) -> Q_u` adds generalized control forces (see ocp.py)."""
    nominal = system.nominal
    q_nom, q_dot_nom = initial_state(nominal, t0)
    rows = structure(nominal, t0, q_nom).independent
    n, m = system.n_coordinates, len(rows)
    t = ca.SX.sym("t")
    x, z = ca.SX.sym("x", 2 * n), ca.SX.sym("z", n + m)
    theta = ca.SX.sym("theta", len(system.names))
    n_u = controls.size1_in(1) if controls is not None else 0
    u = ca.SX.sym("u", n_u)
    ode, alg = _residual(system, list(rows), t, x, z, theta)
    if controls is not None:
        alg[:n] -= controls(x[:n], u)
    return DAE(system, tuple(rows), t, x, z, theta, u, ode, alg, t0, q_nom, q_dot_nom)


def _residual(system: ParametricSystem, rows: list[int], t, x, z, theta) -> tuple:
    """(ode, alg) of the module docstring's DAE without controls: the rp formulation's
    residual at p = [t0 = 0, w, s = 1, d(theta)], w 1 on the rows not in `rows`, whose
    multipliers are 0 and whose equations are dropped."""
    n, m = system.n_coordinates, system.nominal.n_rows
    residual = FORMULATIONS[FORMULATION].residual(system.over_data, "projection")
    mask = np.ones(m)
    mask[rows] = 0.0
    lam = ca.SX.zeros(m, 1)
    lam[rows] = z[n:]
    p = ca.vertcat(0.0, mask, np.ones(m), system.data(theta))
    ode, alg = residual(t, x, ca.vertcat(z[:n], lam), p)
    return ode, ca.vertcat(alg[:n], alg[n:][rows])


def _held_constraints(dae: DAE):
    """(phi, phi_q) of (t, q, theta) over the DAE's rows and the rows holding the joints'
    `initial:` values (runtime/initial_holds.py; optimal/system.py's held_positions), and
    all their rows."""
    system, rows = dae.system, list(dae.rows)
    if "held_positions" not in system.functions:
        return system["phi"], system["phi_q"], rows
    t, q = ca.MX.sym("t"), ca.MX.sym("q", dae.n)
    th = ca.MX.sym("theta", dae.theta.numel())
    held = system["held_positions"](q, th)
    phi = ca.vertcat(system["phi"](t, q, th)[rows], held)
    phi_q = ca.vertcat(system["phi_q"](t, q, th)[rows, :], ca.jacobian(held, q))
    return (ca.Function("phi", [t, q, th], [phi]), ca.Function("phi_q", [t, q, th], [phi_q]),
            list(range(phi.numel())))


def initial_state_function(dae: DAE) -> ca.Function:
    """x0(theta): consistent positions and velocities (differentiable in theta). Positions:
    numerics.kkt.closest_point (the runtime's assembly) to the file's pose at theta (where
    the joints' `initial:` values placed the bodies, with those values held), over the DAE's
    rows, from the nominal assembled pose; its derivative is the implicit one. Velocities:
    the least-squares step onto the velocity constraints (and the held rates)."""
    system, rows, t0 = dae.system, list(dae.rows), dae.t0
    th = ca.MX.sym("theta", dae.theta.numel())
    phi, phi_q, held_rows = _held_constraints(dae)
    closest = kkt.closest_point(phi, phi_q, held_rows)
    q0 = closest(dae.q_assembled, t0, system["initial_guess"](th), th)[0]
    guess = system["file_velocities"](q0, th)
    jac = system["phi_q"](t0, q0, th)[rows, :]
    nu = system["nu"](t0, q0, th)[rows]
    if "held_rates" in system.functions:
        held_jac, targets = system["held_rates"](q0, th)
        jac, nu = ca.vertcat(jac, held_jac), ca.vertcat(nu, targets)
    q_dot0 = guess + jac.T @ ca.solve(jac @ jac.T, nu - jac @ guess)
    return ca.Function("x0", [th], [ca.vertcat(q0, q_dot0)], ["theta"], ["x0"])


def algebraic_function(dae: DAE) -> ca.Function:
    """z(t, x, p) = [q_ddot, lam] solving alg = 0: numerics.kkt.saddle with M, P, F and gamma
    read off alg (linear in z), in an MX graph, so outputs can be written in x alone (what
    adjoint sweeps need)."""
    n, zeros = dae.n, ca.DM.zeros(dae.z.numel())
    q_ddot = dae.z[:n]
    rest = ca.substitute(dae.alg, dae.z, zeros)  # [-F; -gamma]
    mass, jac = ca.jacobian(dae.alg[:n], q_ddot), ca.jacobian(dae.alg[n:], q_ddot)
    parts = ca.Function("kkt", [dae.t, dae.x, dae.p], [mass, jac, -rest[:n], -rest[n:]])
    t, x, p = ca.MX.sym("t"), ca.MX.sym("x", dae.x.numel()), ca.MX.sym("p", dae.p.numel())
    m, a, f, gamma = parts(t, x, p)
    saddle = kkt.saddle(parts.sparsity_out(0), parts.sparsity_out(1))
    v_dot, lam = saddle(m, a, f, gamma, ca.DM.zeros(jac.size1()))
    return ca.Function("z", [t, x, p], [ca.vertcat(v_dot, lam)], ["t", "x", "p"], ["z"])


def consistent_algebraic(dae: DAE, x0: np.ndarray, theta: np.ndarray, u=None) -> np.ndarray:
    """z = [q_ddot, lam] solving alg = 0 at (t0, x0)."""
    p = np.concatenate([theta, np.zeros(dae.u.numel()) if u is None else u])
    return algebraic_function(dae)(dae.t0, x0, p).full().ravel()


def body_columns(system: ParametricSystem) -> ca.Function:
    """Results columns (docs/format.md order, without t) of (t, q, q_dot, q_ddot, lam, theta),
    lam over every row of phi."""
    nominal = system.nominal
    n, nb = nominal.n_coordinates, nominal.n_bodies
    t, theta = ca.SX.sym("t"), ca.SX.sym("theta", len(system.names))
    q, q_dot, q_ddot = (ca.SX.sym(name, n) for name in ("q", "q_dot", "q_ddot"))
    lam = ca.SX.sym("lam", nominal.n_rows)
    omega, alpha = nominal["body_rates"](q, q_dot, q_ddot)
    per_body = [ca.vertcat(q[3 * k:3 * k + 3], q[3 * nb + 4 * k:3 * nb + 4 * k + 4],
                           q_dot[3 * k:3 * k + 3], omega[:, k], q_ddot[3 * k:3 * k + 3],
                           alpha[:, k]) for k in range(nb)]
    force, torque = system["reactions"](t, q, q_dot, lam, theta)
    per_joint = [ca.vertcat(force[:, j], torque[:, j]) for j in range(len(nominal.joints))]
    kinetic, potential = system["energy"](t, q, q_dot, theta)
    violation = ca.mmax(ca.fabs(system["phi"](t, q, theta)))
    elements = system["element_outputs"](t, q, q_dot, theta)  # contacts and stops
    derived = system["readings"](t, q, q_dot, q_ddot, force, torque, theta)  # joints, outputs
    values = ca.vertcat(*per_body, *per_joint, kinetic + potential, violation, elements, derived)
    return ca.Function("body_columns", [t, q, q_dot, q_ddot, lam, theta], [values],
                       ["t", "q", "q_dot", "q_ddot", "lam", "theta"], ["columns"])


def columns_function(dae: DAE) -> tuple[list[str], ca.Function]:
    """Results columns (docs/format.md order, without t) of (t, x, z, theta)."""
    q, q_dot, q_ddot, lam_rows = dae.split(dae.x, dae.z)
    values = body_columns(dae.system)(dae.t, q, q_dot, q_ddot,
                                      dae.full_multipliers(lam_rows), dae.theta)
    return column_names(dae.system.nominal)[1:], ca.Function(
        "columns", [dae.t, dae.x, dae.z, dae.theta], [values], ["t", "x", "z", "theta"],
        ["columns"])
