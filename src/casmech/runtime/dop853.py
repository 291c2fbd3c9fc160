"""Hairer's DOP853 (an explicit Runge-Kutta pair of order 8 with 5th- and 3rd-order error
estimates and a 7th-order interpolant) over an output grid, as scipy's
`solve_ivp(method="DOP853", t_eval=times)` takes its steps: the same initial step, error norm
and step controller, and the states on the grid from each step's interpolant.

Two paths, the same steps: where the ODE (and the projection) are functions loaded from a
compiled library (backends.rk_library.entry), the whole call runs in C
(backends/c/casmech_rk.c, the coefficient tables passed in from scipy's); otherwise scipy's own
DOP853 stepper over the CasADi function. The tables are read from scipy's
`scipy.integrate._ivp.dop853_coefficients` (a private module) so that the C driver and the
Python path integrate with the very same numbers (docs/decisions/dop853.md).

`project(t, x) -> x`, optional, maps each accepted step's end state onto a manifold (the
derivative the next step starts from is evaluated at the projected state) and each output
state interpolated within the step (which is interpolated before the projection).

A right-hand side that is not finite fails at once (FAILED_RATES in the message: as
CVODES's regularity check), as do a step size below 10 ulps of t (TOO_SMALL) and more than
max_steps accepted steps in one call; each a RuntimeError that the driver narrows to an output
interval (runtime.driver, runtime.nonfinite.interval_failure).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

RATES_FAILED = '"RK_RHSFUNC_FAIL"'  # in the message of a right-hand side not finite
TOO_SMALL = "the step size fell below 10 ulps of t"
MAX_STEPS = 100_000  # accepted steps in one call unless the caller sets max_steps


@dataclass
class Stats:
    """A call's counts: accepted and rejected steps, ODE evaluations, projections."""

    accepted: int = 0
    rejected: int = 0
    evaluations: int = 0
    projections: int = 0


def _coefficients():
    from scipy.integrate._ivp import dop853_coefficients as tables

    return tables


@dataclass
class Dop853:
    """DOP853 for `ode` (t, x) -> x_dot (a CasADi Function: inputs named t and x, others
    empty; its first output the derivative) and an optional `project` (t, x) -> x of the same
    form. `use_c`: False forces the Python path (True: C where the functions allow it)."""

    ode: ca.Function
    rtol: float
    atol: float
    project: ca.Function | None = None
    max_step: float = np.inf
    first_step: float | None = None
    max_steps: int = MAX_STEPS
    use_c: bool = True
    last: Stats = field(default_factory=Stats)

    def __post_init__(self):
        self._c = self._c_parts() if self.use_c else None

    @property
    def compiled(self) -> bool:
        """Whether calls run in C."""
        return self._c is not None

    def __call__(self, t0: float, times, x) -> np.ndarray:
        """The states at `times` (increasing, after t0) from x at t0, one column per time;
        self.last holds the call's counts."""
        times = np.ascontiguousarray(times, float)
        x = np.ascontiguousarray(np.ravel(x), float)
        if not len(x):
            self.last = Stats()
            return np.zeros((0, len(times)))
        if self._c is not None:
            return self._run_c(float(t0), times, x)
        return self._run_python(float(t0), times, x)

    # the C path
    def _c_parts(self):
        from casmech.backends import rk_library

        run = rk_library.driver()
        ode = rk_library.entry(self.ode)
        project = None if self.project is None else rk_library.entry(self.project)
        if run is None or ode is None or (self.project is not None and project is None):
            return None
        t = _coefficients()
        arrays = [np.ascontiguousarray(v, float) for v in (
            t.A, t.B, t.C, t.E3, t.E5, t.D)]
        tableau = rk_library.Tableau(
            t.N_STAGES, t.N_STAGES_EXTENDED, t.INTERPOLATOR_POWER - 3,
            *(rk_library.pointer(a) for a in arrays), 7.0)
        settings = rk_library.Settings(
            self.rtol, self.atol, self.max_step, self.first_step or 0.0, *_controller(),
            self.max_steps)
        n = self.ode.nnz_in(self.ode.name_in().index("x"))
        work = np.zeros((t.N_STAGES_EXTENDED + t.INTERPOLATOR_POWER + 6) * n)
        return run, rk_library, ode, project, arrays, tableau, settings, work

    def _run_c(self, t0: float, times: np.ndarray, x: np.ndarray) -> np.ndarray:
        run, lib, ode, project, _, tableau, settings, work = self._c
        import ctypes

        out = np.full((len(times), len(x)), np.nan)
        stats = np.zeros(lib.COUNT, np.int64)
        reached = ctypes.c_double()
        status = run(ctypes.byref(tableau), ctypes.byref(settings), ctypes.byref(ode.struct),
                     None if project is None else ctypes.byref(project.struct), len(x), t0,
                     lib.pointer(x), len(times), lib.pointer(times), lib.pointer(out),
                     lib.pointer(work), stats.ctypes.data_as(ctypes.POINTER(ctypes.c_longlong)),
                     ctypes.byref(reached))
        self.last = Stats(int(stats[lib.ACCEPTED]), int(stats[lib.REJECTED]),
                          int(stats[lib.EVALUATIONS]), int(stats[lib.PROJECTIONS]))
        if status != lib.DONE:
            raise _failure(status, reached.value, {lib.TOO_SMALL: "too small",
                                                   lib.MAX_STEPS: "max steps",
                                                   lib.EVAL_FAILED: "failed",
                                                   lib.NOT_FINITE: "not finite"}[status],
                           out[:int(stats[lib.OUTPUTS])].T, self.max_steps)
        return out.T

    # the Python path: scipy's stepper
    def _run_python(self, t0: float, times: np.ndarray, x: np.ndarray) -> np.ndarray:
        from scipy.integrate import DOP853

        stats = self.last = Stats()
        ode, project = _numeric(self.ode), _numeric(self.project)

        def rates(t, y):
            value = ode(t, y)
            if not np.isfinite(value).all():
                raise _failure(4, t, "not finite", out[:, :done], self.max_steps)
            return value

        out = np.full((len(x), len(times)), np.nan)
        done = 0
        solver = DOP853(rates, t0, x, times[-1], max_step=self.max_step, rtol=self.rtol,
                        atol=self.atol, first_step=self.first_step)
        while done < len(times) and solver.t < times[-1]:
            if stats.accepted >= self.max_steps:
                raise _failure(2, solver.t, "max steps", out[:, :done], self.max_steps)
            if solver.step() is not None or solver.status == "failed":
                raise _failure(1, solver.t, "too small", out[:, :done], self.max_steps)
            stats.accepted += 1
            t = solver.t
            upto = int(np.searchsorted(times, t, side="right"))
            if upto > done:
                out[:, done:upto] = solver.dense_output()(times[done:upto])
                if project is not None:
                    for j in range(done, upto):
                        out[:, j] = project(times[j], out[:, j])
                        stats.projections += 1
                done = upto
            if project is not None:
                solver.y = project(t, solver.y)
                solver.f = solver.fun(t, solver.y)
                stats.projections += 1
        stats.evaluations = solver.nfev
        return out


def _controller() -> tuple[float, float, float]:
    """scipy's step controller's SAFETY, MIN_FACTOR, MAX_FACTOR."""
    from scipy.integrate._ivp import rk

    return rk.SAFETY, rk.MIN_FACTOR, rk.MAX_FACTOR


def _numeric(function: ca.Function | None):
    """function (t, x) -> its first output as a float vector (runtime.buffers: NumPy memory
    bound to the function's buffer), or None."""
    if function is None:
        return None
    from casmech.runtime.buffers import BufferedCall

    names = function.name_in()
    i_t, i_x = (names.index("t") if "t" in names else None), names.index("x")
    buffered = BufferedCall(function, stoppable=False)
    args: list = [None] * function.n_in()

    def call(t, x):
        if i_t is not None:
            args[i_t] = t
        args[i_x] = x
        return buffered(*args)[0].ravel()

    return call


class Failure(RuntimeError):
    """A DOP853 call that stopped before the end: `outputs`, the states computed on the grid
    before it (one column per time), and the time reached."""

    def __init__(self, message: str, t: float, outputs: np.ndarray):
        super().__init__(message)
        self.t, self.outputs = t, outputs


def _failure(status: int, t: float, kind: str, outputs: np.ndarray, max_steps: int) -> Failure:
    messages = {
        "too small": f"DOP853 failed at t = {t:.10g}: {TOO_SMALL}",
        "max steps": f"DOP853 failed at t = {t:.10g}: more than {max_steps} steps in one call",
        "failed": f"DOP853 failed at t = {t:.10g}: the right-hand side's evaluation failed",
        "not finite": f"DOP853 failed near t = {t:.10g}: the right-hand side is not finite "
                      f"({RATES_FAILED})"}
    return Failure(messages[kind], t, np.array(outputs, copy=True))


def from_options(ode: ca.Function, options: dict) -> Dop853:
    """DOP853 for `ode` from CVODES's options as a run sets them (reltol, abstol, and where
    given max_step_size, step0 and max_num_steps: runtime.contact_steps)."""
    return Dop853(ode, options["reltol"], options["abstol"],
                  max_step=options.get("max_step_size", np.inf),
                  first_step=options.get("step0"),
                  max_steps=options.get("max_num_steps", MAX_STEPS))
