"""An embedded pair of Hermite interpolants over one step of an ODE solver, built from the
states and derivatives the solver has already computed, no evaluation of the ODE: the cubic
through (y, f) at the step's ends t and t + h, and the quintic through (y, f) at t - h_prev
too (the previous step's start). runtime.dop853 takes its outputs from the quintic where the
estimate below is small enough (docs/decisions/method-auto.md), backends/c/casmech_rk.c the
same in C.

In the step's unit s = (t_out - t) / h, with m = h f, D = y_new - y:
    cubic(s) = y + s m0 + s^2 c2 + s^3 c3,  c2 = 3 D - 2 m0 - m1,  c3 = m0 + m1 - 2 D
    quintic(s) = cubic(s) + s^2 (s - 1)^2 (alpha + beta s)
where alpha and beta make the quintic pass through y_prev with slope h f_prev at s = -r,
r = h_prev / h. The difference of the two, at most max(|alpha|, |alpha + beta|) / 16 over
the step, is the estimate: in the solver's scaled RMS norm (atol + rtol max(|y|, |y_new|)),
times max(1, r), so that on y' = lambda y with both steps inside DOP853's stability region the
quintic's error stays below 1.6 estimates for any r (tests/unit/numerics/test_hermite_pair.py).
"""

from __future__ import annotations

import numpy as np


def coefficients(y_prev, f_prev, y, f, y_new, f_new, h_prev: float, h: float) -> np.ndarray:
    """(m0, c2, c3, alpha, beta) as rows (5 x n): the pair over the step from (y, f) at t to
    (y_new, f_new) at t + h, the previous step from (y_prev, f_prev) at t - h_prev."""
    r = h_prev / h
    m0, m1, delta = h * f, h * f_new, y_new - y
    c2, c3 = 3 * delta - 2 * m0 - m1, m0 + m1 - 2 * delta
    d0 = y_prev - (y - r * m0 + r * r * c2 - r * r * r * c3)  # the cubic's miss at s = -r
    d1 = h * f_prev - (m0 - 2 * r * c2 + 3 * r * r * c3)  # and its slope's
    g, g_slope = r * r * (1 + r) * (1 + r), -2 * r * (1 + r) * (1 + 2 * r)  # s^2 (s - 1)^2
    beta = (d1 - g_slope * d0 / g) / g
    alpha = d0 / g + r * beta
    return np.array([m0, c2, c3, alpha, beta])


def estimate(pair: np.ndarray, y, y_new, h_prev: float, h: float, rtol: float,
             atol: float) -> float:
    """The bound on |quintic - cubic| over the step in the scaled RMS norm, times max(1, r)."""
    alpha, beta = pair[3], pair[4]
    bound = np.maximum(np.abs(alpha), np.abs(alpha + beta)) / 16
    scale = atol + rtol * np.maximum(np.abs(y), np.abs(y_new))
    return float(np.sqrt(np.mean((bound / scale) ** 2))) * max(1.0, h_prev / h)


def quintic(pair: np.ndarray, y, s) -> np.ndarray:
    """The quintic at the step's units s (one column each)."""
    return cubic(pair, y, s) + _correction(pair, s)


def cubic(pair: np.ndarray, y, s) -> np.ndarray:
    """The cubic at the step's units s (one column each)."""
    s = np.asarray(s, float)[None, :]
    m0, c2, c3 = (row[:, None] for row in pair[:3])
    return y[:, None] + s * (m0 + s * (c2 + s * c3))


def _correction(pair: np.ndarray, s) -> np.ndarray:
    s = np.asarray(s, float)[None, :]
    alpha, beta = pair[3][:, None], pair[4][:, None]
    return s * s * (s - 1) * (s - 1) * (alpha + beta * s)
