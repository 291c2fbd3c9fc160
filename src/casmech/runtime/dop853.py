"""Hairer's DOP853 (an explicit Runge-Kutta pair of order 8 with 5th- and 3rd-order error
estimates and a 7th-order interpolant) over an output grid, as scipy's
`solve_ivp(method="DOP853", t_eval=times)` takes its steps: the same initial step, error norm
and step controller, and the states on the grid from each step's interpolant.

Two paths, the same steps: where the ODE (and the projection) are functions loaded from a
compiled library (backends.rk_library.entry), the whole call runs in C
(backends/c/casmech_rk.c, the coefficient tables and controller constants passed in from
numerics.dop853_tableau, a copy of scipy's that a test holds equal to them); otherwise each
step is one call of a CasADi Function of its 12 stages under scipy's controller in Python
(runtime.dop853_steps). docs/decisions/dop853.md.

`free_outputs` (method auto's, where it bounds the step by the stiffness probe:
runtime.stiffness.stable_step; off by default, so a named `method: dop853` takes scipy's steps
and outputs): an output step after the call's first takes its outputs from the quintic of
numerics.hermite_pair (the states and derivatives at the step's ends and the previous step's
start) where that pair's estimate is below HERMITE_BELOW, instead of DOP853's interpolant and
its 3 extra evaluations; not with a projection. docs/decisions/method-auto.md.

`project(t, x) -> x`, optional, maps each accepted step's end state onto a manifold (the
derivative the next step starts from is evaluated at the projected state) and each output
state interpolated within the step (which is interpolated before the projection).

A right-hand side that is not finite fails at once (FAILED_RATES in the message: as
CVODES's regularity check), as do a step size below 10 ulps of t (TOO_SMALL) and more than
max_steps accepted steps between output times (CVODES's max_num_steps); each a RuntimeError
that the driver narrows to an output interval (runtime.driver, nonfinite.interval_failure).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from casmech.core.options import DynamicsSolver
from casmech.errors import Interrupted
from casmech.numerics import dop853_tableau as tableau_module
from casmech.runtime.buffers import BOUND_ENTRIES

RATES_FAILED = '"RK_RHSFUNC_FAIL"'  # in the message of a right-hand side not finite
TOO_SMALL = "the step size fell below 10 ulps of t"
MAX_STEPS = DynamicsSolver().max_steps  # accepted steps between output times (the option's)
# the Hermite pair's estimate below which its quintic gives a step's outputs (free_outputs):
# the quintic's error then below 1.6 x 0.3 of the tolerance's scale on y' = lambda y
# (numerics.hermite_pair), half the error a DOP853 step is accepted with; DOP853's
# interpolant otherwise. docs/decisions/method-auto.md
HERMITE_BELOW = 0.3
FREE_OUTPUTS = "dop853_free_outputs"  # the integrator option that sets free_outputs


@dataclass
class Stats:
    """A call's counts: accepted and rejected steps, ODE evaluations, projections, and the
    output steps interpolated by the Hermite pair (free_outputs: each saved T_EXTRA
    evaluations)."""

    accepted: int = 0
    rejected: int = 0
    evaluations: int = 0
    projections: int = 0
    hermite: int = 0


class _CCall:
    """What the C path builds once per Dop853: the driver, its arguments that do not change
    between calls (the tableau, settings and entry points by reference, the work vector, the
    counters and the time reached), and the state, output times and outputs of a call held in
    arrays of its own (grown to the longest grid asked for, up to runtime.buffers'
    BOUND_ENTRIES outputs; a longer grid's are made for its call), so a call passes pointers
    made once instead of converting NumPy arrays to pointers (each conversion costs more than
    copying a small array). One Dop853 is not to be called from two threads at once (the work
    vector never was)."""

    def __init__(self, run, lib, kept: tuple, work: np.ndarray, n: int):
        import ctypes

        ode, project, _, tableau, settings = kept  # kept: what the pointers point into
        self.run, self.lib, self._kept, self.n = run, lib, kept, n
        self.stats = np.zeros(lib.COUNT, np.int64)
        self.reached = ctypes.c_double()
        self.head = (ctypes.byref(tableau), ctypes.byref(settings), ctypes.byref(ode.struct),
                     None if project is None else ctypes.byref(project.struct))
        self.tail = (lib.pointer(work), self.stats.ctypes.data_as(
            ctypes.POINTER(ctypes.c_longlong)), ctypes.byref(self.reached))
        self._work, self._x = work, np.empty(n)
        self._x_p = lib.pointer(self._x)
        self._grid: tuple = (0, None, None, None, None)

    def buffers(self, x: np.ndarray, times: np.ndarray):
        """(x, times, outputs) pointers holding this call's x and times, and the outputs (the
        leading len(times) rows of the kept array, NaN)."""
        m = len(times)
        grid = self._grid
        if m > grid[0]:
            times_kept, out = np.empty(m), np.empty((m, self.n))
            grid = (m, times_kept, out, self.lib.pointer(times_kept), self.lib.pointer(out))
            if m * self.n <= BOUND_ENTRIES:
                self._grid = grid
        _, times_kept, out, times_p, out_p = grid
        self._x[:] = x  # (not np.copyto: its Python dispatcher)
        times_kept[:m] = times
        out = out[:m]
        out.fill(np.nan)
        return self._x_p, times_p, out_p, out


@dataclass
class Dop853:
    """DOP853 for `ode` (t, x) -> x_dot (a CasADi Function: inputs named t and x, others
    empty; its first output the derivative) and an optional `project` (t, x) -> x of the same
    form. `use_c`: False forces the Python path (True: C where the functions allow it).
    `free_outputs`: outputs from the Hermite pair where its estimate allows (the module's
    docstring)."""

    ode: ca.Function
    rtol: float
    atol: float
    project: ca.Function | None = None
    max_step: float = np.inf
    first_step: float | None = None
    max_steps: int = MAX_STEPS
    use_c: bool = True
    free_outputs: bool = False
    last: Stats = field(default_factory=Stats)

    def __post_init__(self):
        self._c = self._c_parts() if self.use_c else None

    @property
    def hermite_below(self) -> float:
        """The Hermite pair's threshold: HERMITE_BELOW where free_outputs, else 0 (never)."""
        return HERMITE_BELOW if self.free_outputs and self.project is None else 0.0

    @property
    def compiled(self) -> bool:
        """Whether calls run in C."""
        return self._c is not None

    def __call__(self, t0: float, times, x) -> np.ndarray:
        """The states at `times` (increasing, from t0 on) from x at t0, one column per time
        (x itself at times equal to t0); self.last holds the call's counts."""
        times = np.ascontiguousarray(times, float)
        x = np.ascontiguousarray(x, float).reshape(-1)
        at_start = 0 if not len(times) or times[0] > t0 else \
            int(np.searchsorted(times, t0, side="right"))
        if not len(x) or at_start == len(times):
            self.last = Stats()
            return np.repeat(x[:, None], len(times), axis=1)
        run = self._run_c if self._c is not None else self._run_python
        states = run(float(t0), times[at_start:], x)
        return np.hstack([np.repeat(x[:, None], at_start, axis=1), states]) if at_start \
            else states

    # the C path
    def _c_parts(self) -> _CCall | None:
        if not all(_loaded(f) for f in (self.ode, self.project) if f is not None):
            return None  # (an interpreted bundle imports no code generation: backends.*)
        from casmech.backends import rk_library

        run = rk_library.driver()
        ode = rk_library.entry(self.ode)
        project = None if self.project is None else rk_library.entry(self.project)
        if run is None or ode is None or (self.project is not None and project is None):
            return None
        t = tableau_module
        arrays = [np.ascontiguousarray(v, float) for v in (
            t.A, t.B, t.C, t.E3, t.E5, t.D)]
        tableau = rk_library.Tableau(
            t.N_STAGES, t.N_STAGES_EXTENDED, t.INTERPOLATOR_POWER - 3,
            *(rk_library.pointer(a) for a in arrays), float(t.ERROR_ORDER))
        settings = rk_library.Settings(
            self.rtol, self.atol, self.max_step, self.first_step or 0.0, t.SAFETY, t.MIN_FACTOR,
            t.MAX_FACTOR, self.max_steps, self.hermite_below)
        n = self.ode.nnz_in(self.ode.name_in().index("x"))
        work = np.zeros((t.N_STAGES_EXTENDED + t.INTERPOLATOR_POWER + 8) * n)
        return _CCall(run, rk_library, (ode, project, arrays, tableau, settings), work, n)

    def _run_c(self, t0: float, times: np.ndarray, x: np.ndarray) -> np.ndarray:
        c, lib = self._c, self._c.lib
        m = len(times)
        x_p, times_p, out_p, out = c.buffers(x, times)
        status = c.run(*c.head, len(x), t0, x_p, m, times_p, out_p, *c.tail)
        stats = c.stats.tolist()
        self.last = Stats(stats[lib.ACCEPTED], stats[lib.REJECTED], stats[lib.EVALUATIONS],
                          stats[lib.PROJECTIONS], stats[lib.HERMITE])
        if status != lib.DONE:
            raise _failure({lib.TOO_SMALL: "too small", lib.MAX_STEPS: "max steps",
                            lib.EVAL_FAILED: "failed", lib.NOT_FINITE: "not finite"}[status],
                           c.reached.value, out[:stats[lib.OUTPUTS]].T, self.max_steps)
        return out.copy().T

    # the Python path: runtime.dop853_steps
    def _python_parts(self):
        from casmech.runtime import dop853_steps as steps
        from casmech.runtime.buffers import BufferedCall

        if getattr(self, "_python", None) is None:
            self._python = (
                BufferedCall(steps.step_function(self.ode), stoppable=False),
                BufferedCall(steps.dense_function(self.ode), stoppable=False),
                _numeric(self.ode), _numeric(self.project), steps)
        return self._python

    def _run_python(self, t0: float, times: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The Python path's call; an Interrupted (a signal, a controller's fault inside the
        ODE: runtime.cancel) carries in `outputs` the states computed so far (NaN beyond)."""
        out = np.full((len(y), len(times)), np.nan)
        try:
            return self._steps(t0, times, y, out)
        except Interrupted as interrupted:
            interrupted.outputs = out
            raise

    def _steps(self, t0: float, times: np.ndarray, y: np.ndarray, out: np.ndarray
               ) -> np.ndarray:
        from casmech.numerics import hermite_pair

        step, dense, ode, project, steps = self._python_parts()
        stats = self.last = Stats()
        done, t, t_bound = 0, t0, float(times[-1])

        def fail(kind: str, at: float) -> Failure:
            return _failure(kind, at, out[:, :done], self.max_steps)

        def rates(at: float, state: np.ndarray) -> np.ndarray:
            stats.evaluations += 1
            value = ode(at, state)
            if not np.isfinite(value).all():
                raise fail("not finite", at)
            return value

        f, since_output, below = rates(t, y), 0, self.hermite_below
        previous = None  # (y, f, h) of the step before, for the Hermite pair
        h_abs = min(self.first_step, t_bound - t0) if self.first_step else steps.initial_step(
            rates, t, y, f, t_bound, self.max_step, self.rtol, self.atol)
        while done < len(times) and t != t_bound:
            if since_output >= self.max_steps:
                raise fail("max steps", t)
            min_step = 10 * abs(np.nextafter(t, np.inf) - t)
            h_abs = self.max_step if h_abs > self.max_step else max(h_abs, min_step)
            rejected = False
            while True:
                if h_abs < min_step:
                    raise fail("too small", t)
                t_new = min(t + h_abs, t_bound)
                h = t_new - t
                h_abs = abs(h)
                y_new, f_new, norm, K = step(t, y, f, h, self.rtol, self.atol)
                stats.evaluations += T_STAGES
                if not np.isfinite(K).all():
                    raise fail("not finite", t)
                accepted, h_abs = steps.next_step(h_abs, norm.item(), rejected)
                if accepted:
                    break
                rejected = True
                stats.rejected += 1
            stats.accepted += 1
            since_output += 1
            y_new, f_new = y_new.ravel(), f_new.ravel()
            upto = int(np.searchsorted(times, t_new, side="right"))
            if upto > done:
                since_output = 0
                pair = None if previous is None or not below else hermite_pair.coefficients(
                    previous[0], previous[1], y, f, y_new, f_new, previous[2], h)
                if pair is not None and hermite_pair.estimate(
                        pair, y, y_new, previous[2], h, self.rtol, self.atol) < below:
                    out[:, done:upto] = hermite_pair.quintic(pair, y, (times[done:upto] - t) / h)
                    stats.hermite += 1
                else:
                    F = dense(t, h, y, y_new, f_new, K)[0]
                    stats.evaluations += T_EXTRA
                    out[:, done:upto] = steps.interpolate(F, t, h, y, times[done:upto])
                if project is not None:
                    for j in range(done, upto):
                        out[:, j] = project(times[j], out[:, j])
                        stats.projections += 1
                done = upto
            previous = y, f, h
            t, y, f = t_new, y_new, f_new
            if project is not None:
                y = project(t, y)
                stats.projections += 1
                f = rates(t, y)
        return out


T_STAGES = tableau_module.N_STAGES  # evaluations of one step attempt (its last: f_new)
T_EXTRA = tableau_module.N_STAGES_EXTENDED - tableau_module.N_STAGES - 1  # the interpolant's


def in_c(ode: ca.Function, entry: bool = True) -> bool:
    """Whether DOP853 over `ode` runs in C: `ode` loaded from a compiled library (with a C
    entry point: `entry`; False for a function from which a compiled one is derived, as the
    loops' projected ODE of a compiled bundle) and the driver built. Else its Python path
    evaluates 12 stages a step in CasADi."""
    if not _loaded(ode):
        return False
    from casmech.backends import rk_library

    return rk_library.driver() is not None and (
        not entry or rk_library.entry(ode) is not None)


def _loaded(function: ca.Function) -> bool:
    """Whether `function` may have a C entry point (backends.rk_library.entry): it is, or
    calls, a function loaded from a library."""
    return function.class_name() == "External" or (
        function.class_name() == "MXFunction"
        and any(f.class_name() == "External" for f in function.find_functions()))


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


def _failure(kind: str, t: float, outputs: np.ndarray, max_steps: int) -> Failure:
    messages = {
        "too small": f"DOP853 failed at t = {t:.10g}: {TOO_SMALL}",
        "max steps": f"DOP853 failed at t = {t:.10g}: more than {max_steps} steps before the "
                     "next output time",
        "failed": f"DOP853 failed at t = {t:.10g}: the right-hand side's evaluation failed",
        "not finite": f"DOP853 failed near t = {t:.10g}: the right-hand side is not finite "
                      f"({RATES_FAILED})"}
    return Failure(messages[kind], t, np.array(outputs, copy=True))


def from_options(ode: ca.Function, options: dict) -> Dop853:
    """DOP853 for `ode` from CVODES's options as a run sets them (reltol, abstol, and where
    given max_step_size, step0 and max_num_steps: runtime.contact_steps; FREE_OUTPUTS where
    method auto bounds the step: runtime.joint_dynamics)."""
    return Dop853(ode, options["reltol"], options["abstol"],
                  max_step=options.get("max_step_size", np.inf),
                  first_step=options.get("step0"),
                  max_steps=options.get("max_num_steps", MAX_STEPS),
                  free_outputs=options.get(FREE_OUTPUTS, False))
