"""Multiple shooting with fixed RK4 steps (rockit's MultipleShooting): the transcription of
an ODE x' = f(t, x, c) on the nodes of the control grid.

Each control interval [t_k, t_k + h] is integrated by `steps` classical Runge-Kutta steps
from the node state x_k; the end must meet x_{k+1} (optimal/joint_ocp.py adds the closure
projection). The controls inside the interval come from the control shape
(optimal/control_shapes.py), evaluated at each stage's time.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca


@dataclass(frozen=True)
class MultipleShooting:
    steps: int = 4  # RK4 steps per control interval

    def interval(self, opti, f: ca.Function, t0, h, x_begin, control, guess) -> tuple:
        """(state at the end, [(t, x) at every step's end]) of one interval; `control(s)`:
        the control at fraction s of it; `guess` unused (no variables inside)."""
        dt = h / self.steps
        x, points = x_begin, []
        for j in range(self.steps):
            t = t0 + j * dt
            s0, s1 = j / self.steps, (j + 1) / self.steps
            c0, cm, c1 = control(s0), control(0.5 * (s0 + s1)), control(s1)
            k1 = f(t, x, c0)
            k2 = f(t + dt / 2, x + dt / 2 * k1, cm)
            k3 = f(t + dt / 2, x + dt / 2 * k2, cm)
            k4 = f(t + dt, x + dt * k3, c1)
            x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            points.append((t + dt, s1, x))
        return x, points
