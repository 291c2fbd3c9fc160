"""Initial guesses for optimal control: a rest-to-rest interpolation between the initial pose
and a pose meeting the terminal conditions, with the controls of inverse dynamics.

    target  Gauss-Newton (least-squares steps) on [Phi(q); c(q) - c*] from the initial pose,
            c the terminal columns that depend on positions only (an `e0`, a CM coordinate)
    path    q(s) = the point of Phi = 0 closest to the straight line between the two poses
            (Euler parameters renormalised; numerics.kkt.closest_point, started from the
            runtime's Newton projection), timed by s = 3 tau^2 - 2 tau^3 (rest to rest)
    rates   q_dot, q_ddot from dq/ds and d2q/ds2 by CasADi through the rootfinder (the
            implicit function's derivatives), q_dot projected onto Phi_q q_dot = nu
    u       per interval, the least-squares solution (multipliers and controls) of the equations
            of motion at its midpoint, clipped to the bounds

For a chain of revolute joints this is close to a straight line in joint space; IPOPT starts
from states that nearly satisfy the dynamics, where a forward simulation of a gravity-loaded arm
with guessed controls flails through poses far from the optimum.
"""

from __future__ import annotations

from functools import cached_property

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.numerics import kkt
from casmech.optimal.dae import DAE
from casmech.runtime.assembly import newton, solve_velocities

MAX_ITERATIONS = 50
TOLERANCE = 1e-10
MAX_STEP = 0.1  # largest change of a coordinate per Gauss-Newton step (far targets)


@record
class Guess:
    """States at any time of the horizon and piecewise-constant controls."""

    dae: DAE
    q_start: np.ndarray
    q_end: np.ndarray
    horizon: float

    def line(self, s):
        """The straight-line pose at path parameter s, Euler parameters renormalised (numbers
        or a CasADi expression of s)."""
        nb = self.dae.system.nominal.n_bodies
        q = (1 - s) * self.q_start + s * self.q_end
        parts = [q[:3 * nb]] + [q[3 * nb + 4 * k:3 * nb + 4 * k + 4] for k in range(nb)]
        unit = [p / (ca.norm_2(p) if isinstance(p, ca.MX) else np.linalg.norm(p))
                for p in parts[1:]]
        return ca.vertcat(parts[0], *unit) if isinstance(q, ca.MX) else \
            np.concatenate([parts[0], *unit])

    def positions(self, tau: float) -> np.ndarray:
        """The projected straight-line pose at path parameter tau in [0, 1] (the runtime's
        Newton projection)."""
        return newton(self.dae.system.nominal, self.dae.t0, self.line(tau))

    @cached_property
    def path(self) -> ca.Function:
        """(q_guess, s) -> (q, dq/ds, d2q/ds2): the closest point of Phi = 0 to line(s)."""
        dae, system = self.dae, self.dae.system
        closest = kkt.closest_point(system["phi"], system["phi_q"], dae.rows)
        guess, s = ca.MX.sym("q_guess", dae.n), ca.MX.sym("s")
        q = closest(guess, dae.t0, self.line(s), ca.DM(system.values))[0]
        dq = ca.jacobian(q, s)
        return ca.Function("path", [guess, s], [q, dq, ca.jacobian(dq, s)])

    def rates(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, q_dot, q_ddot) at time t: s(tau) = 3 tau^2 - 2 tau^3, tau = (t - t0) / T."""
        tau = (t - self.dae.t0) / self.horizon
        s = float(np.clip(3 * tau ** 2 - 2 * tau ** 3, 0.0, 1.0))
        s_dot, s_ddot = (6 * tau - 6 * tau ** 2) / self.horizon, (6 - 12 * tau) / self.horizon ** 2
        q, dq, d2q = (np.array(v).ravel() for v in self.path(self.positions(s), s))
        return q, dq * s_dot, d2q * s_dot ** 2 + dq * s_ddot

    def state(self, t: float) -> np.ndarray:
        q, q_dot, _ = self.rates(t)
        return np.concatenate([q, solve_velocities(self.dae.system.nominal, t, q, q_dot)])


def target_pose(dae: DAE, columns: ca.Function, names: list[str], terminal: dict,
                q0: np.ndarray) -> np.ndarray:
    """A pose with Phi = 0 meeting the terminal conditions that depend on positions only
    (columns independent of q_dot, q_ddot and lam)."""
    t, n = dae.t0, dae.n
    values = columns(t, dae.x, dae.z, ca.DM.zeros(dae.theta.numel()))
    rates = ca.vertcat(dae.x[n:], dae.z)
    kept = [(names.index(name), value) for name, value in terminal.items()
            if not ca.depends_on(values[names.index(name)], rates)]
    q = dae.x[:n]
    phi = dae.system["phi"](t, q, ca.DM.zeros(dae.theta.numel()))
    residual = ca.vertcat(phi, *[values[r] - v for r, v in kept])
    f = ca.Function("target", [q], [residual, ca.jacobian(residual, q)])
    q_k = np.array(q0, float)
    for _ in range(MAX_ITERATIONS):
        r, jac = (np.array(v) for v in f(q_k))
        if np.max(np.abs(r)) <= TOLERANCE:
            break
        step = np.linalg.lstsq(jac, -r.ravel(), rcond=None)[0]
        q_k = q_k + step * min(1.0, MAX_STEP / np.max(np.abs(step)))
    return q_k


def inverse_dynamics_controls(dae: DAE, guess_rates, times: np.ndarray, lower, upper):
    """Per interval: least-squares (lam, u) of the equations of motion at the midpoint."""
    n, n_z = dae.n, dae.z.numel()
    unknowns = ca.vertcat(dae.z[n:], dae.u)
    residual = dae.alg[:n]
    parts = ca.Function("id", [dae.t, dae.x, dae.z, dae.u],
                        [ca.jacobian(residual, unknowns),
                         ca.substitute(residual, unknowns, ca.DM.zeros(unknowns.numel()))])
    controls = []
    for begin, end in zip(times[:-1], times[1:], strict=True):
        t = 0.5 * (begin + end)
        q, q_dot, q_ddot = guess_rates(t)
        z = np.concatenate([q_ddot, np.zeros(n_z - n)])
        matrix, rest = (np.array(v) for v in parts(t, np.concatenate([q, q_dot]), z,
                                                  np.zeros(dae.u.numel())))
        solution = np.linalg.lstsq(matrix, -rest.ravel(), rcond=None)[0]
        controls.append(np.clip(solution[n_z - n:], lower, upper))
    return np.array(controls)
