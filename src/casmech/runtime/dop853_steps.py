"""DOP853's step and interpolant as CasADi Functions over an ODE Function, and scipy's step
controller over them in Python: runtime.dop853's path where the ODE has no C entry point (an
interpreted bundle's SX, a mapped tree's MX, a parametric library's bound functions).

One call of `step` evaluates the step's 12 stages inside CasADi (an MX function calling the
ODE 12 times), so a step costs one Python-to-CasADi call instead of 12 (scipy's stepper calls
its right-hand side from Python stage by stage). The controller is scipy's RungeKutta._step_impl
and select_initial_step, the error norm DOP853._estimate_error_norm, the interpolant
Dop853DenseOutput (as the C driver's, backends/c/casmech_rk.c), with the coefficients of
numerics.dop853_tableau: the same steps as scipy's `solve_ivp(method="DOP853")`, states equal
to roundoff (tests/unit/runtime/test_dop853.py).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.numerics import dop853_tableau as T


def _call(ode: ca.Function, t, x):
    """ode's first output at (t, x), its other inputs empty."""
    names = ode.name_in()
    inputs = {name: ca.MX(ode.sparsity_in(name)) for name in names}
    if "t" in names:
        inputs["t"] = t
    inputs["x"] = x
    return ode.call(inputs)[ode.name_out()[0]]


def _combination(stages: list, row: np.ndarray, count: int):
    """sum_j row[j] K_j over the first `count` stages (zero coefficients left out)."""
    terms = [float(row[j]) * stages[j] for j in range(count) if row[j] != 0.0]
    return sum(terms[1:], terms[0])


def step_function(ode: ca.Function) -> ca.Function:
    """(t, y, f, h, rtol, atol) -> (y_new, f_new, error norm, K): one DOP853 step from (t, y)
    with f = ode(t, y), its stages K (n x 13, the last f_new)."""
    n = ode.nnz_in(ode.name_in().index("x"))
    t, h, rtol, atol = (ca.MX.sym(name) for name in ("t", "h", "rtol", "atol"))
    y, f = ca.MX.sym("y", n), ca.MX.sym("f", n)
    stages = [f]
    for s in range(1, T.N_STAGES):
        stages.append(_call(ode, t + T.C[s] * h, y + _combination(stages, T.A[s], s) * h))
    y_new = y + h * _combination(stages, T.B, T.N_STAGES)
    f_new = _call(ode, t + h, y_new)
    stages.append(f_new)
    scale = atol + ca.fmax(ca.fabs(y), ca.fabs(y_new)) * rtol
    err5 = _combination(stages, T.E5, T.N_STAGES + 1) / scale
    err3 = _combination(stages, T.E3, T.N_STAGES + 1) / scale
    n5, n3 = ca.sumsqr(err5), ca.sumsqr(err3)
    denominator = n5 + 0.01 * n3
    norm = ca.if_else(denominator == 0, 0, ca.fabs(h) * n5 / ca.sqrt(
        ca.fmax(denominator, np.finfo(float).tiny) * n))
    return ca.Function("dop853_step", [t, y, f, h, rtol, atol],
                       [y_new, f_new, norm, ca.horzcat(*stages)],
                       ["t", "y", "f", "h", "rtol", "atol"], ["y_new", "f_new", "norm", "K"])


def dense_function(ode: ca.Function) -> ca.Function:
    """(t_old, h, y_old, y, f, K) -> F (n x 7): the interpolant of the step from (t_old,
    y_old) to y (f its derivative) with stages K, its three extra stages evaluated here."""
    n = ode.nnz_in(ode.name_in().index("x"))
    t, h = ca.MX.sym("t"), ca.MX.sym("h")
    y_old, y, f = ca.MX.sym("y_old", n), ca.MX.sym("y", n), ca.MX.sym("f", n)
    K = ca.MX.sym("K", n, T.N_STAGES + 1)
    stages = [K[:, j] for j in range(T.N_STAGES + 1)]
    for s in range(T.N_STAGES + 1, T.N_STAGES_EXTENDED):
        stages.append(_call(ode, t + T.C[s] * h, y_old + _combination(stages, T.A[s], s) * h))
    delta = y - y_old
    rows = [delta, h * stages[0] - delta, 2 * delta - h * (f + stages[0])]
    rows += [h * _combination(stages, T.D[r], T.N_STAGES_EXTENDED) for r in range(len(T.D))]
    return ca.Function("dop853_dense", [t, h, y_old, y, f, K], [ca.horzcat(*rows)],
                       ["t", "h", "y_old", "y", "f", "K"], ["F"])


def interpolate(F: np.ndarray, t_old: float, h: float, y_old: np.ndarray,
                times: np.ndarray) -> np.ndarray:
    """The interpolant F (n x 7) at `times` (one column each): scipy's Dop853DenseOutput."""
    x = (np.asarray(times, float) - t_old) / h
    y = np.zeros((len(y_old), len(x)))
    for i, row in enumerate(reversed(F.T)):
        y += row[:, None]
        y *= x if i % 2 == 0 else 1 - x
    return y + y_old[:, None]


def initial_step(rates, t0: float, y0: np.ndarray, f0: np.ndarray, t_bound: float,
                 max_step: float, rtol: float, atol: float) -> float:
    """scipy's select_initial_step (one evaluation of `rates`)."""
    interval = t_bound - t0
    if interval == 0.0:
        return 0.0
    scale = atol + np.abs(y0) * rtol
    d0, d1 = _rms(y0 / scale), _rms(f0 / scale)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, interval)
    f1 = rates(t0 + h0, y0 + h0 * f0)
    d2 = _rms((f1 - f0) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1 / (T.ERROR_ORDER + 1))
    return min(100 * h0, h1, interval, max_step)


def _rms(v: np.ndarray) -> float:
    return float(np.linalg.norm(v) / v.size ** 0.5)


def next_step(h_abs: float, norm: float, rejected: bool) -> tuple[bool, float]:
    """(accepted, the next step size) from a step of size h_abs with this error norm, after a
    rejection in the same step or not: scipy's controller."""
    exponent = -1 / (T.ERROR_ORDER + 1)
    if norm < 1:
        factor = T.MAX_FACTOR if norm == 0 else min(T.MAX_FACTOR, T.SAFETY * norm ** exponent)
        return True, h_abs * (min(1, factor) if rejected else factor)
    return False, h_abs * max(T.MIN_FACTOR, T.SAFETY * norm ** exponent)
