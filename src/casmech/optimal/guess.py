"""Initial guesses for optimal control: a rest-to-rest interpolation between the initial pose
and a pose meeting the terminal conditions, with the controls of inverse dynamics.

    target  Gauss-Newton (least-squares steps) on [Phi(q); c(q) - c*] from the initial pose,
            c the terminal columns that depend on positions only (an `e0`, a CM coordinate)
    path    q(t) = Newton projection onto Phi = 0 of the straight line between the two poses
            (Euler parameters renormalised), timed by s = 3 tau^2 - 2 tau^3 (rest to rest)
    rates   q_dot, q_ddot by central differences of the path, q_dot projected onto Phi_q q_dot = nu
    u       per interval, the least-squares solution (multipliers and controls) of the equations
            of motion at its midpoint, clipped to the bounds

For a chain of revolute joints this is close to a straight line in joint space; IPOPT starts
from states that nearly satisfy the dynamics, where a forward simulation of a gravity-loaded arm
with guessed controls flails through poses far from the optimum.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from casmech.optimal.dae import DAE
from casmech.runtime.assembly import newton, solve_velocities

MAX_ITERATIONS = 50
TOLERANCE = 1e-10
MAX_STEP = 0.1  # largest change of a coordinate per Gauss-Newton step (far targets)
DELTA = 1e-4  # central-difference step in the path parameter


@dataclass(frozen=True)
class Guess:
    """States at any time of the horizon and piecewise-constant controls."""

    dae: DAE
    q_start: np.ndarray
    q_end: np.ndarray
    horizon: float

    def positions(self, tau: float) -> np.ndarray:
        """The projected straight-line pose at path parameter tau in [0, 1]."""
        nb = self.dae.system.nominal.n_bodies
        q = (1 - tau) * self.q_start + tau * self.q_end
        for k in range(nb):
            p = q[3 * nb + 4 * k:3 * nb + 4 * k + 4]
            q[3 * nb + 4 * k:3 * nb + 4 * k + 4] = p / np.linalg.norm(p)
        return newton(self.dae.system.nominal, self.dae.t0, q)

    def _path(self, s: float) -> np.ndarray:
        return self.positions(float(np.clip(s, 0.0, 1.0)))

    def rates(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, q_dot, q_ddot) at time t: s(tau) = 3 tau^2 - 2 tau^3, tau = (t - t0) / T."""
        tau = (t - self.dae.t0) / self.horizon
        s = 3 * tau ** 2 - 2 * tau ** 3
        s_dot, s_ddot = (6 * tau - 6 * tau ** 2) / self.horizon, (6 - 12 * tau) / self.horizon ** 2
        lo, mid, hi = (self._path(s + d) for d in (-DELTA, 0.0, DELTA))
        dq, d2q = (hi - lo) / (2 * DELTA), (hi - 2 * mid + lo) / DELTA ** 2
        return mid, dq * s_dot, d2q * s_dot ** 2 + dq * s_ddot

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
