"""numerics.hermite_pair: the cubic and quintic Hermite interpolants of one step against
polynomials they must reproduce, their order on a harmonic oscillator's exact solution, and the
estimate against the quintic's error on y' = lambda y inside DOP853's stability region."""

import numpy as np
import pytest

from casmech.numerics import hermite_pair as H

S = np.linspace(0.0, 1.0, 41)


def _pair(solution, derivative, t: float, h_prev: float, h: float):
    """The pair over [t, t + h] after a step of h_prev, from an exact solution (y, f at the
    three points)."""
    points = (t - h_prev, t, t + h)
    ys = [solution(p) for p in points]
    fs = [derivative(p) for p in points]
    return H.coefficients(ys[0], fs[0], ys[1], fs[1], ys[2], fs[2], h_prev, h), ys


@pytest.mark.parametrize("h_prev", [0.3, 1.0, 2.5])
def test_quintic_reproduces_quintics_and_cubic_cubics(h_prev):
    rng = np.random.default_rng(5)
    quintic = np.polynomial.Polynomial(rng.normal(size=(6,)))
    cubic = np.polynomial.Polynomial(rng.normal(size=(4,)))
    t, h = 0.7, 0.4
    for poly, interpolant in ((quintic, H.quintic), (cubic, H.cubic), (cubic, H.quintic)):
        pair, ys = _pair(lambda p, q=poly: np.array([q(p)]),
                         lambda p, q=poly: np.array([q.deriv()(p)]), t, h_prev, h)
        # a polynomial of the interpolant's degree or less: exact to roundoff of O(1) values
        np.testing.assert_allclose(interpolant(pair, ys[1], S)[0], poly(t + S * h),
                                   rtol=1e-12, atol=1e-12)
    pair, ys = _pair(lambda p: np.array([cubic(p)]), lambda p: np.array([cubic.deriv()(p)]),
                     t, h_prev, h)
    # cubic data: the quintic adds nothing, so the estimate of their difference is zero
    assert H.estimate(pair, ys[1], ys[2], h_prev, h, 1e-3, 1e-5) < 1e-9


def _oscillator_errors(h: float) -> tuple[float, float]:
    """The largest errors of the quintic and the cubic over a step of h (after one of h) on
    the harmonic oscillator y = (cos 3t, -3 sin 3t)."""
    omega = 3.0

    def solution(t):
        return np.array([np.cos(omega * t), -omega * np.sin(omega * t)])

    def derivative(t):
        return np.array([-omega * np.sin(omega * t), -omega**2 * np.cos(omega * t)])

    t = 0.4
    pair, ys = _pair(solution, derivative, t, h, h)
    exact = np.array([solution(t + s * h) for s in S]).T
    return (np.abs(H.quintic(pair, ys[1], S) - exact).max(),
            np.abs(H.cubic(pair, ys[1], S) - exact).max())


def test_orders_on_a_harmonic_oscillator():
    coarse, fine = _oscillator_errors(0.04), _oscillator_errors(0.02)
    quintic_order = np.log2(coarse[0] / fine[0])
    cubic_order = np.log2(coarse[1] / fine[1])
    # local errors O(h^6) and O(h^4): their observed orders within 0.15 of that
    np.testing.assert_allclose(quintic_order, 6.0, rtol=0, atol=0.15)
    np.testing.assert_allclose(cubic_order, 4.0, rtol=0, atol=0.15)


def _linear_case(z: complex, r: float):
    """The pair over the step s in [0, 1] of y = exp(z s) (the real and imaginary parts as two
    states; step h = 1, the previous of r) and the exact values."""
    def solution(s):
        value = np.exp(z * s)
        return np.array([value.real, value.imag])

    def derivative(s):
        value = z * np.exp(z * s)
        return np.array([value.real, value.imag])

    pair, ys = _pair(solution, derivative, 0.0, r, 1.0)
    return pair, ys, np.array([solution(s) for s in S]).T


@pytest.mark.parametrize("r", [0.2, 1.0, 3.0, 30.0])
def test_the_estimate_bounds_the_quintics_error_in_the_stability_region(r):
    worst = 0.0
    for radius in np.linspace(0.1, 6.2, 16):
        for angle in np.linspace(np.pi / 2, np.pi, 7):
            z = radius * np.exp(1j * angle) / max(1.0, r)  # both steps |z| <= 6.2
            pair, ys, exact = _linear_case(z, r)
            error = np.abs(H.quintic(pair, ys[1], S) - exact).max(axis=1)
            # the estimate bounds the pair's difference over the step, state by state (the
            # difference computed from O(1) values: roundoff 1e-15)
            bound = np.maximum(np.abs(pair[3]), np.abs(pair[3] + pair[4])) / 16
            difference = np.abs(H.quintic(pair, ys[1], S) - H.cubic(pair, ys[1], S)).max(1)
            assert np.all(difference <= bound + 1e-15)
            # the quintic's error (its RMS over the states, beyond roundoff of 1e-14) per
            # estimate (atol 1, rtol 0: unscaled)
            estimate = H.estimate(pair, ys[1], ys[2], r, 1.0, 0.0, 1.0)
            excess = max(np.sqrt(np.mean(error**2)) - 1e-14, 0.0) / estimate
            worst = max(worst, excess)
    # the module's claim: the quintic's error below 1.6 estimates (measured up to ~1.5)
    assert worst < 1.6


def test_the_estimate_is_the_scaled_rms_norm():
    pair, ys, _ = _linear_case(-2.0 + 1.0j, 2.0)
    bound = np.maximum(np.abs(pair[3]), np.abs(pair[3] + pair[4])) / 16
    scale = 1e-4 + 1e-2 * np.maximum(np.abs(ys[1]), np.abs(ys[2]))
    expected = np.sqrt(np.mean((bound / scale) ** 2)) * 2.0
    np.testing.assert_allclose(H.estimate(pair, ys[1], ys[2], 2.0, 1.0, 1e-2, 1e-4), expected,
                               rtol=1e-14, atol=0)  # the same arithmetic written out
