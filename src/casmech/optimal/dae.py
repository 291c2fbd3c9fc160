"""The index-1 DAE of a parametric system, its consistent initial state and its outputs.

    x = [q, q_dot]    z = [q_ddot, lam]    p = [theta, u]
    ode: [q_dot; q_ddot]
    alg: [M q_ddot + Phi_q^T lam - Q - B^T u;  Phi_q q_ddot - gamma]

over the independent constraint rows at the assembled pose (redundant rows dropped). The initial
state is a function of theta: positions are casmech's assembly (runtime/assembly.py: driver
continuation, then least-squares Newton from the file's pose, itself a function of theta)
unrolled as a CasADi graph with the iteration counts the nominal assembly takes plus one (so the
result is the same map near the nominal theta, and its derivative the derivative of the
converged point, also when the mechanism has degrees of freedom and the pose depends on the path
Newton takes); velocities are the file's
velocities corrected by the least-squares step onto Phi_q q_dot = nu.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from casmech.compiler.checks import structure
from casmech.optimal.system import ParametricSystem
from casmech.runtime import assembly
from casmech.runtime.assembly import initial_state
from casmech.runtime.results import column_names


@dataclass(frozen=True)
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
    q, q_dot, q_ddot, lam = x[:n], x[n:], z[:n], z[n:]
    phi_q = system["phi_q"](t, q, theta)[list(rows), :]
    forces = system["generalized_forces"](t, q, q_dot, theta)
    if controls is not None:
        forces += controls(q, u)
    alg = ca.vertcat(system["mass_matrix"](q, theta) @ q_ddot + phi_q.T @ lam - forces,
                     phi_q @ q_ddot - system["gamma"](t, q, q_dot, theta)[list(rows)])
    return DAE(system, tuple(rows), t, x, z, theta, u, ca.vertcat(q_dot, q_ddot), alg, t0,
               q_nom, q_dot_nom)


def _newton_counts(dae: DAE) -> list[tuple[float | None, int]]:
    """(driver scale or None, Newton iterations) of each stage of the nominal assembly, as
    runtime/assembly.py runs it (continuation stages, then the unscaled solve)."""
    nominal, t0 = dae.system.nominal, dae.t0
    q = assembly.initial_guess(nominal)
    steps = max(1, math.ceil(assembly.driver_span(nominal, t0) / assembly.MAX_DRIVER_STEP))
    stages = [(k / steps, 1e-8 if k < steps else assembly.POSITION_TOLERANCE)
              for k in range(1, steps + 1)] + [(None, assembly.POSITION_TOLERANCE)]
    counts = []
    for scale, tolerance in stages:
        count = 0
        while count < assembly.MAX_ITERATIONS:
            if scale is None:
                phi, phi_q = nominal.vector("phi", t0, q), nominal.matrix("phi_q", t0, q)
            else:
                phi, phi_q = nominal.evaluate("phi_scaled", t0, q, scale)
                phi = phi.ravel()
            if np.max(np.abs(phi), initial=0.0) <= tolerance:
                break
            q = q + np.linalg.lstsq(phi_q, -phi, rcond=None)[0]
            count += 1
        counts.append((scale, count))
    return counts


def _assembly_graph(dae: DAE, theta) -> ca.MX:
    """Assembled positions as a function of theta: the nominal Newton iterations unrolled, one
    more per stage, least-squares steps on the independent rows."""
    system, rows, t0 = dae.system, list(dae.rows), dae.t0
    q = system["initial_guess"](theta)
    for scale, count in _newton_counts(dae):
        for _ in range(count + 1):
            if scale is None:
                phi, jac = system["phi"](t0, q, theta), system["phi_q"](t0, q, theta)
            else:
                phi, jac = system["phi_scaled"](t0, q, scale, theta)
            phi, jac = phi[rows], jac[rows, :]
            q = q - jac.T @ ca.solve(jac @ jac.T, phi)
    return q


def initial_state_function(dae: DAE) -> ca.Function:
    """x0(theta): consistent positions and velocities (differentiable in theta)."""
    system, rows, t0 = dae.system, list(dae.rows), dae.t0
    th = ca.MX.sym("theta", dae.theta.numel())
    q0 = _assembly_graph(dae, th)
    guess = system["file_velocities"](q0, th)
    jac = system["phi_q"](t0, q0, th)[rows, :]
    rhs = system["nu"](t0, q0, th)[rows] - jac @ guess
    q_dot0 = guess + jac.T @ ca.solve(jac @ jac.T, rhs)
    return ca.Function("x0", [th], [ca.vertcat(q0, q_dot0)], ["theta"], ["x0"])


def algebraic_function(dae: DAE) -> ca.Function:
    """z(t, x, p) = [q_ddot, lam] solving alg = 0 (alg is linear in z): a sparse linear solve
    in an MX graph, so outputs can be written in x alone (what adjoint sweeps need)."""
    zeros = ca.DM.zeros(dae.z.numel())
    parts = ca.Function("kkt", [dae.t, dae.x, dae.p],
                        [ca.jacobian(dae.alg, dae.z), ca.substitute(dae.alg, dae.z, zeros)])
    t, x, p = ca.MX.sym("t"), ca.MX.sym("x", dae.x.numel()), ca.MX.sym("p", dae.p.numel())
    matrix, residual = parts(t, x, p)
    return ca.Function("z", [t, x, p], [ca.solve(matrix, -residual)], ["t", "x", "p"], ["z"])


def consistent_algebraic(dae: DAE, x0: np.ndarray, theta: np.ndarray, u=None) -> np.ndarray:
    """z = [q_ddot, lam] solving alg = 0 at (t0, x0)."""
    p = np.concatenate([theta, np.zeros(dae.u.numel()) if u is None else u])
    return algebraic_function(dae)(dae.t0, x0, p).full().ravel()


def columns_function(dae: DAE) -> tuple[list[str], ca.Function]:
    """Results columns (docs/format.md order, without t) of (t, x, z, theta)."""
    system, nominal = dae.system, dae.system.nominal
    t, theta = dae.t, dae.theta
    q, q_dot, q_ddot, lam_rows = dae.split(dae.x, dae.z)
    lam = dae.full_multipliers(lam_rows)
    nb = nominal.n_bodies
    omega, alpha = nominal["body_rates"](q, q_dot, q_ddot)
    per_body = [ca.vertcat(q[3 * k:3 * k + 3], q[3 * nb + 4 * k:3 * nb + 4 * k + 4],
                           q_dot[3 * k:3 * k + 3], omega[:, k], q_ddot[3 * k:3 * k + 3],
                           alpha[:, k]) for k in range(nb)]
    force, torque = system["reactions"](t, q, q_dot, lam, theta)
    per_joint = [ca.vertcat(force[:, j], torque[:, j]) for j in range(len(nominal.joints))]
    kinetic, potential = system["energy"](t, q, q_dot, theta)
    violation = ca.mmax(ca.fabs(system["phi"](t, q, theta)))
    elements = nominal["element_outputs"](t, q, q_dot)  # contacts and stops (nominal values)
    values = ca.vertcat(*per_body, *per_joint, kinetic + potential, violation, elements)
    return column_names(nominal)[1:], ca.Function("columns", [t, dae.x, dae.z, theta], [values],
                                                  ["t", "x", "z", "theta"], ["columns"])
