"""numerics.kkt: the closest point of a constraint manifold (a rootfinder) and the saddle-point
solve, against closed forms and dense NumPy."""

import casadi as ca
import numpy as np

from casmech.numerics import kkt


def sphere():
    """Phi(t, q, theta) = [|q|^2 - theta^2; q_2 - t]: a circle of radius sqrt(theta^2 - t^2)
    in the plane q_2 = t, in 3-D (one degree of freedom)."""
    t, q, theta = ca.SX.sym("t"), ca.SX.sym("q", 3), ca.SX.sym("theta")
    phi = ca.vertcat(ca.dot(q, q) - theta ** 2, q[2] - t)
    return (ca.Function("phi", [t, q, theta], [phi]),
            ca.Function("phi_q", [t, q, theta], [ca.jacobian(phi, q)]))


def closest_on_circle(t, q_ref, theta):
    """Closed form: the reference's in-plane part scaled to the circle's radius."""
    radius = np.sqrt(theta ** 2 - t ** 2)
    planar = q_ref[:2] * radius / np.linalg.norm(q_ref[:2])
    return np.array([*planar, t])


def test_closest_point_of_a_circle_and_its_derivative():
    phi, phi_q = sphere()
    closest = kkt.closest_point(phi, phi_q, [0, 1])
    t, q_ref, theta = 0.3, np.array([0.8, -0.9, 0.5]), 1.1
    guess = closest_on_circle(t, q_ref, theta) + 1e-3  # a start near the root
    q = np.array(closest(guess, t, q_ref, theta)[0]).ravel()
    # Newton to |KKT| <= 1e-14 on O(1) numbers: roundoff
    np.testing.assert_allclose(q, closest_on_circle(t, q_ref, theta), rtol=0, atol=1e-13)
    # the implicit derivative dq/d(theta, q_ref) against central differences of the closed form
    inputs = ca.MX.sym("inputs", 4)
    q_out = closest(guess, t, inputs[1:], inputs[0])[0]
    jacobian = ca.Function("dq", [inputs], [ca.jacobian(q_out, inputs)])
    x = np.array([theta, *q_ref])
    got = np.array(jacobian(x))
    step = 1e-6
    fd = np.column_stack([
        (closest_on_circle(t, (x + step * e)[1:], (x + step * e)[0])
         - closest_on_circle(t, (x - step * e)[1:], (x - step * e)[0])) / (2 * step)
        for e in np.eye(4)])
    # central differences with h = 1e-6 on O(1) functions: h^2 truncation, 1e-10 roundoff / h
    np.testing.assert_allclose(got, fd, rtol=0, atol=1e-8)


def test_saddle_equals_the_dense_solve_with_masked_rows():
    rng = np.random.default_rng(4)
    n, m = 6, 3
    root = rng.standard_normal((n, n))
    mass = root @ root.T + n * np.eye(n)
    jac = rng.standard_normal((m, n))
    forces, gamma, w = rng.standard_normal(n), rng.standard_normal(m), np.array([0, 1.0, 0])
    solve = kkt.saddle(ca.Sparsity.dense(n, n), ca.Sparsity.dense(m, n))
    v_dot, lam = (np.array(v).ravel() for v in solve(mass, jac, forces, gamma, w))
    lhs = np.block([[mass, jac.T], [jac, -np.diag(w)]])
    expected = np.linalg.solve(lhs, np.concatenate([forces, gamma]))
    # two direct solves of a well-conditioned 9 x 9 system: roundoff
    np.testing.assert_allclose(np.concatenate([v_dot, lam]), expected, rtol=0, atol=1e-12)
