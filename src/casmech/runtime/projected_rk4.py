"""Classical Runge-Kutta steps on the augmented-Lagrangian ODE, each followed by a projection
back onto the position and velocity constraints, with the number of steps per output interval
chosen by step doubling: the integrator runtime.dynamics falls back to at singular
configurations (IFToMM A02's flat poses), where both DAEs fail.

Why a projection after every step: near a flat pose two branches of the constraint manifold
cross. Each step starts on the manifold and moves along the motion's tangent, so the step's end
lies far nearer the branch the mechanism is on than the other one (they part linearly from the
crossing, the step errs by h^5), and the mass-orthogonal projection takes the nearest. On A02
N = 2 every fixed step tried kept both formulations on the branch this way
(tests/integration/runtime/test_projected_rk4); projecting only at the outputs, or IDAS on the
same ODE, did not always (docs/decisions/singular-fallback.md).

Error control: an output interval is integrated with n and with 2n steps; the fine result is
kept when |fine - coarse| / 15 (its error for a 4th-order method) is within the tolerance,
weighted as IDAS does (RMS of the error over rtol |x| + atol), for the positions and for the
velocities (unless theirs stalls at a singular pose: ProjectedRK4.error). Otherwise, or for
the next interval, n is scaled to put that estimate at core.options.Fallback.safety. Two
resolutions on different branches disagree by metres, so a branch change in either is rejected
as well. The run's cancellation token is polled at every step (runtime.cancel).

A try whose states are not finite is refined once, by NONFINITE_REFINEMENT (a step too long
for the dynamics may overflow); a second one in a row is a law that is not finite along the
motion (a force law's sqrt of a negative): StatesNotFinite, at once, never up to max_steps.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from casmech.core.options import Fallback
from casmech.formulations import augmented
from casmech.formulations.table import BODY_FORMS
from casmech.runtime import cancel

ORDER = 4  # of the classical Runge-Kutta method
NONFINITE_REFINEMENT = 4  # the step count's factor after a try that is not finite
DEFAULT = Fallback()  # the defaults (core.options)


def rk4_step(functions: dict[str, ca.Function], name: str,
             solve: ca.Function, settings: Fallback = DEFAULT) -> ca.Function:
    """(t, x, h, penalty) -> x after one Runge-Kutta step of x' = [q_dot(q, v), v_dot(t, q, v)]
    (v_dot by `solve`, augmented.accelerations) and the projection of formulations.augmented."""
    form = BODY_FORMS[name]
    project = augmented.projection(functions, name, settings)
    n_q, n_v = solve.size1_in(1), solve.size1_in(2)
    t, x, h, penalty = (ca.MX.sym("t"), ca.MX.sym("x", n_q + n_v), ca.MX.sym("h"),
                        ca.MX.sym("penalty"))

    def rate(time, state):
        q, v = state[:n_q], state[n_q:]
        q_dot = v if form.q_dot is None else functions[form.q_dot](q, v)
        return ca.vertcat(q_dot, solve(time, q, v, penalty)[0])

    k1 = rate(t, x)
    k2 = rate(t + h / 2, x + h / 2 * k1)
    k3 = rate(t + h / 2, x + h / 2 * k2)
    k4 = rate(t + h, x + h * k3)
    stepped = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    q, v = project(t + h, stepped[:n_q], stepped[n_q:], penalty)
    return ca.Function(f"{name}_rk4_step", [t, x, h, penalty], [ca.vertcat(q, v)],
                       ["t", "x", "h", "penalty"], ["x_next"])


class StepFailure(Exception):
    """No step count up to the settings' max_steps met the tolerance (the message says what
    happened)."""


class StatesNotFinite(StepFailure):
    """Two tries in a row whose states were not finite (module docstring)."""


class ProjectedRK4:
    """Advances x = [q, v] from one output time to the next; `accelerations` is the
    (t, q, v, penalty) -> (v_dot, lam) its steps use, for the outputs' columns."""

    def __init__(self, functions: dict[str, ca.Function], name: str, rtol: float, atol: float,
                 settings: Fallback = DEFAULT):
        self.settings = settings
        self.accelerations = augmented.accelerations(functions, name, settings)
        self.step = rk4_step(functions, name, self.accelerations, settings)
        self.n_q = functions["mass_matrix"].size1_in(0)
        self.rtol, self.atol = rtol, atol
        self.coarse = 1  # coarse steps for the next interval
        self.steps = 0  # fine steps taken (kept)
        self.rejected = 0  # output intervals redone with more steps
        self.stalled: list[float] = []  # interval starts kept with stalled velocities (error)

    def advance(self, t0: float, t1: float, x: np.ndarray, penalty: float) -> np.ndarray:
        n, last, last_n, refined = self.coarse, None, None, False
        safety, most = self.settings.safety, self.settings.max_steps
        while 2 * n <= most:
            coarse = self._steps(t0, t1, x, penalty, n)
            fine = self._steps(t0, t1, x, penalty, 2 * n)
            if not (np.all(np.isfinite(coarse)) and np.all(np.isfinite(fine))):
                if refined:
                    raise StatesNotFinite(f"the states were not finite with {n} and {2 * n} "
                                          "steps in the output interval")
                self.rejected += 1
                n, refined = NONFINITE_REFINEMENT * n, True
                continue
            refined = False
            positions, velocities = self.error(coarse, fine)
            # below 2nd order between the two tries: not the 4th-order discretization error
            stalled = last is not None and velocities > last / (n / last_n) ** 2
            if positions <= 1 and (velocities <= 1 or stalled):
                if velocities > 1:
                    self.stalled.append(float(t0))
                measured = max(positions, velocities if velocities <= 1 else 0.0)
                self.coarse = max(1, math.ceil(n * (measured / safety) ** (1 / ORDER)))
                self.steps += 2 * n
                return fine
            self.rejected += 1
            worst = max(positions, velocities)
            growth = (worst / safety) ** (1 / ORDER) if np.isfinite(worst) else math.inf
            n, last, last_n = math.ceil(n * min(max(2.0, growth), 64.0)), velocities, n
        raise StepFailure(f"the error estimate stayed above the tolerance with {most} "
                          "steps in the output interval")

    def error(self, coarse: np.ndarray, fine: np.ndarray) -> tuple[float, float]:
        """Weighted RMS of the fine result's error estimate, (positions, velocities); inf if
        either state is not finite. Two, because at a singular pose the velocity along the
        lost direction is the penalty's: on A02 N = 40 at its flat pose at 10.55 s the
        couplers' spin was 1.6e-3, 3e-5 and 1.5e-7 rad/s with a = 1e4, 1e6 and 1e8 times the
        mass, where it is 0. Two
        resolutions differ there by what no step count removes (1e4 times the tolerance at
        rtol 1e-10 with any of 10 to 160 steps), until the projection removes it past the
        pose, while the positions, which integrate it, met the tolerance. So advance keeps
        an interval whose positions meet the tolerance and whose velocity estimate shrank by
        less than the square of the factor the steps were multiplied by (a 4th-order
        discretization error shrinks by its 4th power; docs/decisions/singular-fallback.md).
        On the whipping chain of tests/integration/runtime, controlling the positions alone left
        10x the error at rtol 1e-8 (3.6e-8 against 3.5e-9 m at t <= 1 s)."""
        if not (np.all(np.isfinite(coarse)) and np.all(np.isfinite(fine))):
            return math.inf, math.inf
        weights = self.rtol * np.abs(fine) + self.atol
        estimate = (fine - coarse) / (2 ** ORDER - 1) / weights
        return (float(np.sqrt(np.mean(estimate[:self.n_q] ** 2))),
                float(np.sqrt(np.mean(estimate[self.n_q:] ** 2))))

    def _steps(self, t0: float, t1: float, x: np.ndarray, penalty: float, n: int) -> np.ndarray:
        h, state = (t1 - t0) / n, ca.DM(x)
        for k in range(n):
            cancel.poll()
            state = self.step(t0 + k * h, state, h, penalty)
        return np.array(state.full()).ravel()
