"""Two optimal control problems written by hand in rockit (rockit-meco 0.6.7, the `bench`
extra), the same physics and the same transcription as casmech solves them from the gallery's
models/ocp_cart_pole_swing_up.yaml and models/ocp_double_pendulum_swing_up.yaml:

    cart-pole swing-up     N = 25, Radau degree 3, |F| <= 20, |y| <= 1 at the nodes,
                           min int F^2, T = 2.5, to rest upright, the cart back at y = 0
    double pendulum        N = 20, Radau degree 3, |tau_1| <= 30, |tau_2| <= 15,
                           min int tau^T tau, T = 2, both links to rest upright

The equations of motion are Lagrange's, derived here by hand (planar, the joint angles about
the global x axis, 0 hanging down); "upright" is written as casmech's terminal conditions are
(the Euler parameter e0 = cos(angle / 2) = 0). The initial guess is the one casmech starts
from by default: the motion under a constant push of 10% of each control's upper bound,
simulated (scipy DOP853), so both solvers start at the same point and reach the same local
optimum. IPOPT's options are casmech's (optimal/ocp.py).

    python benchmarks/rockit_ocp.py      # prints each problem's cost and IPOPT time
"""

from __future__ import annotations

import numpy as np
from casadi import cos, interpolant, sin, vertcat
from scipy.integrate import solve_ivp

G = 9.81
IPOPT = {"ipopt.tol": 1e-10, "ipopt.mumps_pivtol": 1e-4, "ipopt.mumps_pivtolmax": 0.1,
         "ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": False, "record_time": True,
         "expand": True}


def cart_pole_rates(x, force, mc=1.0, mp=0.3, length=1.0):
    """(y, theta, y_dot, theta_dot)' of the cart-pole: a cart on y, a uniform pole hanging
    from it (CM at length/2, inertia mp length^2 / 12 about its CM)."""
    _, theta, y_dot, theta_dot = x[0], x[1], x[2], x[3]
    a = mp * length / 2
    inertia = mp * length ** 2 / 12 + mp * length ** 2 / 4
    # [mc + mp, a cos; a cos, inertia] [y_dd; th_dd] = [F + a sin th_d^2; -a g sin]
    m11, m12, m22 = mc + mp, a * cos(theta), inertia
    f1 = force + a * sin(theta) * theta_dot ** 2
    f2 = -a * G * sin(theta)
    det = m11 * m22 - m12 ** 2
    return vertcat(y_dot, theta_dot, (m22 * f1 - m12 * f2) / det, (m11 * f2 - m12 * f1) / det)


def double_pendulum_rates(x, tau, m=1.0, length=1.0):
    """(a1, a2, a1_dot, a2_dot)' of two uniform links (a2: the elbow's relative angle)."""
    a1, a2, w1, w2 = x[0], x[1], x[2], x[3]
    inertia = m * length ** 2 / 12
    c2, s2 = cos(a2), sin(a2)
    half = length / 2
    # absolute angles phi1 = a1, phi2 = a1 + a2; mass matrix in (a1, a2)
    m22 = m * half ** 2 + inertia
    m12 = m22 + m * length * half * c2
    m11 = inertia + m * half ** 2 + m * length ** 2 + m22 + 2 * m * length * half * c2
    h = m * length * half * s2  # Coriolis coefficient
    gravity1 = (m * half + m * length) * G * sin(a1) + m * half * G * sin(a1 + a2)
    gravity2 = m * half * G * sin(a1 + a2)
    f1 = tau[0] + h * (2 * w1 * w2 + w2 ** 2) - gravity1
    f2 = tau[1] - h * w1 ** 2 - gravity2
    det = m11 * m22 - m12 ** 2
    return vertcat(w1, w2, (m22 * f1 - m12 * f2) / det, (m11 * f2 - m12 * f1) / det)


def _simulated(rates, push, horizon: float, intervals: int) -> np.ndarray:
    """States at the nodes under constant controls `push` (casmech's default guess)."""
    def rhs(t, x):
        return np.array(rates(x, push)).astype(float).ravel()

    times = np.linspace(0, horizon, intervals + 1)
    return solve_ivp(rhs, (0, horizon), np.zeros(4), method="DOP853", rtol=1e-8, atol=1e-10,
                     t_eval=times).y


def cart_pole(intervals: int = 25):
    """(cost, IPOPT's time [s], iterations) of the cart-pole swing-up in rockit."""
    import rockit

    ocp = rockit.Ocp(T=2.5)
    y, theta = ocp.state(), ocp.state()
    y_dot, theta_dot = ocp.state(), ocp.state()
    force = ocp.control()
    rates = cart_pole_rates(vertcat(y, theta, y_dot, theta_dot), force)
    for state, rate in zip((y, theta, y_dot, theta_dot), (rates[0], rates[1], rates[2], rates[3]),
                           strict=True):
        ocp.set_der(state, rate)
    ocp.subject_to(ocp.at_t0(vertcat(y, theta, y_dot, theta_dot)) == 0)
    ocp.subject_to(-20 <= (force <= 20))
    ocp.subject_to(-1 <= (y <= 1), include_first=False)
    ocp.subject_to(ocp.at_tf(cos(theta / 2)) == 0)
    ocp.subject_to(ocp.at_tf(vertcat(theta_dot, y, y_dot)) == 0)
    ocp.add_objective(ocp.integral(force ** 2))
    guess = _simulated(cart_pole_rates, 2.0, 2.5, intervals)
    _initial(ocp, (y, theta, y_dot, theta_dot), guess, 2.5)
    ocp.set_initial(force, 2.0)
    return _solve(ocp, rockit.DirectCollocation(N=intervals, degree=3, scheme="radau"))


def double_pendulum(intervals: int = 20):
    """(cost, IPOPT's time [s], iterations) of the double-pendulum swing-up in rockit."""
    import rockit

    ocp = rockit.Ocp(T=2.0)
    a1, a2, w1, w2 = (ocp.state() for _ in range(4))
    tau = ocp.control(2)
    rates = double_pendulum_rates(vertcat(a1, a2, w1, w2), tau)
    for state, k in zip((a1, a2, w1, w2), range(4), strict=True):
        ocp.set_der(state, rates[k])
    ocp.subject_to(ocp.at_t0(vertcat(a1, a2, w1, w2)) == 0)
    ocp.subject_to(-30 <= (tau[0] <= 30))
    ocp.subject_to(-15 <= (tau[1] <= 15))
    # upright: upper.e0 = cos(a1 / 2) = 0, lower.e0 = cos((a1 + a2) / 2) = 0, at rest
    ocp.subject_to(ocp.at_tf(vertcat(cos(a1 / 2), cos((a1 + a2) / 2))) == 0)
    ocp.subject_to(ocp.at_tf(vertcat(w1, w1 + w2)) == 0)
    ocp.add_objective(ocp.integral(tau[0] ** 2 + tau[1] ** 2))
    push = np.array([3.0, 1.5])
    guess = _simulated(double_pendulum_rates, push, 2.0, intervals)
    _initial(ocp, (a1, a2, w1, w2), guess, 2.0)
    ocp.set_initial(tau, push)
    return _solve(ocp, rockit.DirectCollocation(N=intervals, degree=3, scheme="radau"))


def _initial(ocp, states, guess: np.ndarray, horizon: float) -> None:
    """The guess at the nodes, interpolated linearly in time (rockit 0.6.7's set_initial with
    an array fails in DirectCollocation: `kron` is not imported there)."""
    times = list(np.linspace(0, horizon, guess.shape[1]))
    for state, row in zip(states, guess, strict=True):
        ocp.set_initial(state, interpolant("guess", "linear", [times], list(row))(ocp.t))


def _solve(ocp, method):
    ocp.method(method)
    ocp.solver("ipopt", IPOPT)
    solution = ocp.solve()
    stats = solution.stats
    return (float(solution.value(ocp.objective)), float(stats["t_proc_total"]),
            int(stats["iter_count"]))


if __name__ == "__main__":
    for name, problem in (("cart-pole", cart_pole), ("double pendulum", double_pendulum)):
        cost, seconds, iterations = problem()
        print(f"{name}: cost {cost:.10g}, IPOPT {seconds:.4f} s, {iterations} iterations")
