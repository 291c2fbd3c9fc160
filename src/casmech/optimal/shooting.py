"""Multiple shooting (rockit's MultipleShooting): the transcription of an ODE
x' = f(t, x, c) on the nodes of the control grid, with fixed RK4 steps (MultipleShooting)
or a SUNDIALS integrator on the ODE (SundialsShooting: CVODES or IDAS).

Each control interval [t_k, t_k + h] is integrated from the node state x_k; the end must
meet x_{k+1} (optimal/joint_ocp.py adds the closure projection). The controls inside the
interval come from the control shape (optimal/control_shapes.py).
"""

from __future__ import annotations

from dataclasses import field

import casadi as ca

from casmech.core.records import record


@record
class MultipleShooting:
    steps: int = 4  # RK4 steps per control interval

    def interval(self, opti, f: ca.Function, t0, h, x_begin, control, guess) -> tuple:
        """(state at the end, [(t, s, x) at every step's end]) of one interval; `control(s)`:
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


INTEGRATORS = ("rk4", "cvodes", "idas")  # MultipleShooting's RK4, SundialsShooting's


@record(frozen=False)
class SundialsShooting:
    """Multiple shooting with a SUNDIALS integrator per control interval (rockit's
    MultipleShooting(intg='cvodes')): CVODES or IDAS on the ODE.

    The interval is integrated in its own time s in [0, 1] (t = t0 + s h, so h may be a
    variable: free final time), with the controls c(s) = (1 - s) c(0) + s c(1), which is
    either control shape exactly (optimal/control_shapes.py; the decision parameters
    constant). The integrator reports the state at `outputs` equal fractions of the interval
    (the fine path grid's points); CasADi's forward and adjoint sensitivities of the
    integrator give the NLP its derivatives.
    """

    integrator: str = "cvodes"
    outputs: int = 4  # states reported per interval, the last at its end
    rtol: float = 1e-10
    atol: float = 1e-12
    _made: dict = field(default_factory=dict, repr=False, compare=False)

    def _function(self, f: ca.Function) -> ca.Function:
        """(x0, [c(0); c(1); t0; h]) -> states at the outputs (n x outputs), one per f."""
        if id(f) in self._made:
            return self._made[id(f)][1]
        n, n_c = f.size1_in(1), f.size1_in(2)
        s, x = ca.MX.sym("s"), ca.MX.sym("x", n)
        p = ca.MX.sym("p", 2 * n_c + 2)
        c0, c1, t0, h = p[:n_c], p[n_c:2 * n_c], p[2 * n_c], p[2 * n_c + 1]
        problem = {"t": s, "x": x, "p": p, "ode": h * f(t0 + s * h, x, (1 - s) * c0 + s * c1)}
        grid = [(j + 1) / self.outputs for j in range(self.outputs)]
        made = ca.integrator("interval", self.integrator, problem, 0.0, grid,
                             {"reltol": self.rtol, "abstol": self.atol,
                              "max_num_steps": 100000})
        x0 = ca.MX.sym("x0", n)
        function = ca.Function("shoot", [x0, p], [made(x0=x0, p=p)["xf"]])
        self._made[id(f)] = (f, function)  # f kept: its id stays its own
        return function

    def interval(self, opti, f: ca.Function, t0, h, x_begin, control, guess) -> tuple:
        """(state at the end, [(t, s, x) at every output]) of one interval; `control(s)`:
        the control at fraction s (affine in s); `guess` unused (no variables inside)."""
        states = self._function(f)(x_begin, ca.vertcat(control(0.0), control(1.0), t0, h))
        points = [(t0 + (j + 1) / self.outputs * h, (j + 1) / self.outputs, states[:, j])
                  for j in range(self.outputs)]
        return states[:, -1], points
