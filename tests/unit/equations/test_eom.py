"""r-p equations-of-motion pieces (equations/eom.py via functions.build_functions): mass matrix,
energy, generalized forces of gravity, point forces, torques and springs.

Oracles: the r-p formulas of Haug (1989) ch. 11 written in numpy, Euler's rigid-body equations,
virtual power (Q . q_dot = F . v_P, n . omega) with velocities by finite differences, and the
spring potential's gradient by finite differences.
"""

import numpy as np
import pytest

from tests.helpers.equations import (
    compile_model,
    coordinates,
    force,
    g_matrix,
    model,
    random_unit_p,
    rotation,
    scalar,
    skew,
    stack_q,
    two_free_bodies,
)

GRAVITY = np.array([0.0, 0.0, -9.81])
# Closed forms evaluated two ways in double precision: O(100) flops on entries of O(10-100).
EXACT = {"rtol": 1e-12, "atol": 1e-11}


def block_diag(*blocks):
    out = np.zeros((sum(b.shape[0] for b in blocks), sum(b.shape[1] for b in blocks)))
    row = col = 0
    for b in blocks:
        out[row:row + b.shape[0], col:col + b.shape[1]] = b
        row, col = row + b.shape[0], col + b.shape[1]
    return out


def compiled(rng, forces=(), gravity=(0.0, 0.0, 0.0)):
    bodies = two_free_bodies(rng)
    return bodies, compile_model(model(bodies, forces=forces, gravity=gravity))


def random_state(rng, n_bodies=2):
    """Unit p, and a velocity whose p-parts are tangent: p_dot = 1/2 G^T omega_bar."""
    poses = [(rng.normal(size=3), random_unit_p(rng)) for _ in range(n_bodies)]
    r_dot = rng.normal(size=(n_bodies, 3))
    omega_bar = rng.normal(size=(n_bodies, 3))
    p_dot = [0.5 * g_matrix(p).T @ w for (_, p), w in zip(poses, omega_bar, strict=True)]
    q_dot = np.concatenate([r_dot.ravel(), *p_dot])
    return poses, stack_q(poses), q_dot, r_dot, omega_bar


def test_mass_matrix(rng):
    """blkdiag(m_1 I, m_2 I, 4 G_1^T J_1 G_1, 4 G_2^T J_2 G_2) (q = [r_1, r_2, p_1, p_2])."""
    bodies, functions = compiled(rng)
    poses, q, *_ = random_state(rng)
    expected = block_diag(*[b.mass * np.eye(3) for b in bodies],
                          *[4 * g_matrix(p).T @ b.inertia @ g_matrix(p)
                            for b, (_, p) in zip(bodies, poses, strict=True)])
    np.testing.assert_allclose(functions.matrix("mass_matrix", q), expected, **EXACT)


def test_energy(rng):
    """kinetic = sum 1/2 m v.v + 1/2 omega_bar^T J omega_bar; potential = -sum m g.r."""
    bodies, functions = compiled(rng, gravity=GRAVITY)
    poses, q, q_dot, r_dot, omega_bar = random_state(rng)
    kinetic, potential = (x.item() for x in functions.evaluate("energy", 0.0, q, q_dot))
    expected_kinetic = sum(0.5 * b.mass * v @ v + 0.5 * w @ b.inertia @ w
                           for b, v, w in zip(bodies, r_dot, omega_bar, strict=True))
    expected_potential = -sum(b.mass * GRAVITY @ r for b, (r, _) in zip(bodies, poses, strict=True))
    np.testing.assert_allclose(kinetic, expected_kinetic, **EXACT)
    np.testing.assert_allclose(potential, expected_potential, **EXACT)
    # The same kinetic energy as 1/2 q_dot^T M q_dot (tangent p_dot).
    np.testing.assert_allclose(kinetic, 0.5 * q_dot @ functions.matrix("mass_matrix", q) @ q_dot,
                               **EXACT)


def test_gravity_and_quadratic_velocity_of_free_bodies(rng):
    """Q = [m g; 8 G_dot^T J G_dot p] with G_dot = G(p_dot)."""
    bodies, functions = compiled(rng, gravity=GRAVITY)
    poses, q, q_dot, *_ = random_state(rng)
    p_dots = np.split(q_dot[6:], 2)
    expected = np.concatenate(
        [b.mass * GRAVITY for b in bodies]
        + [8 * g_matrix(pd).T @ b.inertia @ g_matrix(pd) @ p
           for b, (_, p), pd in zip(bodies, poses, p_dots, strict=True)])
    np.testing.assert_allclose(functions.vector("generalized_forces", 0.0, q, q_dot), expected,
                               **EXACT)


def test_rotational_equation_reproduces_euler_equations(rng):
    """Torque-free body: with omega_bar_dot from Euler's equations J w_dot = -w~ J w and
    p_ddot = 1/2 G_dot^T w + 1/2 G^T w_dot, the r-p rotational equation
    4 G^T J G p_ddot - Q_p = -2 p lam_P holds: the residual is parallel to p."""
    bodies, functions = compiled(rng)
    poses, q, q_dot, _, omega_bar = random_state(rng)
    mass = functions.matrix("mass_matrix", q)
    forces = functions.vector("generalized_forces", 0.0, q, q_dot)
    for k, (b, (_, p), w) in enumerate(zip(bodies, poses, omega_bar, strict=True)):
        w_dot = np.linalg.solve(b.inertia, -np.cross(w, b.inertia @ w))
        g_dot = g_matrix(0.5 * g_matrix(p).T @ w)
        p_ddot = 0.5 * g_dot.T @ w + 0.5 * g_matrix(p).T @ w_dot
        block = slice(6 + 4 * k, 10 + 4 * k)
        residual = mass[block, block] @ p_ddot - forces[block]
        np.testing.assert_allclose(residual - (p @ residual) * p, 0.0, **EXACT)


# --- force elements: virtual power ---------------------------------------------------------------

AT = np.array([0.7, -0.4, 1.3])  # global point of application at t = 0 (not the CM)
VALUE = ("1.0 + 0.5*t", "-2*cos(t)", "0.3")
T = 0.4


def value_at(t):
    return np.array([scalar(text).value(t=t) for text in VALUE])


def tangent_velocity(rng, q):
    """A random q_dot with p^T p_dot = 0 for each body (a physical velocity)."""
    q_dot = rng.normal(size=q.size)
    for k in range(2):
        p = q[6 + 4 * k: 10 + 4 * k]
        q_dot[6 + 4 * k: 10 + 4 * k] -= (q_dot[6 + 4 * k: 10 + 4 * k] @ p) * p
    return q_dot


def pose_of(q, k):
    return q[3 * k: 3 * k + 3], q[6 + 4 * k: 10 + 4 * k]


def point_position(q, k, s_bar):
    r, p = pose_of(q, k)
    return r + rotation(p) @ s_bar


def central(fn, q, q_dot, h=1e-6):
    """d/dh fn(q + h q_dot) at 0. The positions and rotations here are quadratic in h, so the
    central difference has no truncation error, only roundoff ~ eps / h ~ 1e-10 per entry."""
    return (fn(q + h * q_dot) - fn(q - h * q_dot)) / (2 * h)


@pytest.mark.parametrize("frame", ["global", "body"])
def test_point_force_virtual_power(frame, rng):
    """Q . q_dot = F . v_P, v_P the velocity of the body point (FD of r + A s_bar)."""
    bodies = two_free_bodies(rng)
    element = force("push", "force", body="b1", at=AT, frame=frame,
                    value=tuple(scalar(text) for text in VALUE))
    functions = compile_model(model(bodies, forces=[element]))
    q0 = coordinates(bodies)
    s_bar = rotation(bodies[0].euler_parameters).T @ (AT - bodies[0].position)
    _, q, _, _, _ = random_state(rng)
    q_dot = tangent_velocity(rng, q)
    f_global = value_at(T) if frame == "global" else rotation(pose_of(q, 0)[1]) @ value_at(T)
    q_force = functions.vector("generalized_forces", T, q, np.zeros_like(q))
    v_point = central(lambda x: point_position(x, 0, s_bar), q, q_dot)
    # FD roundoff ~1e-10 per entry of v_P, times |F| ~ 2.
    np.testing.assert_allclose(q_force @ q_dot, f_global @ v_point, rtol=1e-8, atol=1e-8)
    # The force acts at the file's point: at q0 the point is AT.
    np.testing.assert_allclose(point_position(q0, 0, s_bar), AT, **EXACT)
    assert np.all(q_force[3:6] == 0.0) and np.all(q_force[10:14] == 0.0)  # body 2 untouched


@pytest.mark.parametrize("frame", ["global", "body"])
def test_torque_virtual_power(frame, rng):
    """Q . q_dot = n . omega, omega (global) from omega~ = A_dot A^T (FD of A(p))."""
    bodies = two_free_bodies(rng)
    element = force("twist", "torque", body="b2", frame=frame,
                    value=tuple(scalar(text) for text in VALUE))
    functions = compile_model(model(bodies, forces=[element]))
    _, q, _, _, _ = random_state(rng)
    q_dot = tangent_velocity(rng, q)
    a = rotation(pose_of(q, 1)[1])
    n_global = value_at(T) if frame == "global" else a @ value_at(T)
    a_dot = central(lambda x: rotation(pose_of(x, 1)[1]), q, q_dot)
    omega_tilde = a_dot @ a.T
    omega = np.array([omega_tilde[2, 1], omega_tilde[0, 2], omega_tilde[1, 0]])
    q_force = functions.vector("generalized_forces", T, q, np.zeros_like(q))
    # FD roundoff ~1e-10 per entry of omega, times |n| ~ 2.
    np.testing.assert_allclose(omega_tilde, skew(omega), rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(q_force @ q_dot, n_global @ omega, rtol=1e-8, atol=1e-8)
    assert np.all(q_force[:6] == 0.0)  # a pure torque has no translational part


# --- springs -------------------------------------------------------------------------------------

AT_I, AT_J = np.array([0.5, 0.1, 0.9]), np.array([1.2, 0.4, 0.8])
STIFFNESS, FREE_LENGTH = 35.0, 0.5


def spring_model(rng):
    bodies = two_free_bodies(rng)
    element = force("spring", "tsda", body_i="b1", body_j="b2", at_i=AT_I, at_j=AT_J,
                    stiffness=STIFFNESS, damping=0.0, free_length=FREE_LENGTH)
    functions = compile_model(model(bodies, forces=[element]))
    s_bars = [rotation(b.euler_parameters).T @ (at - b.position)
              for b, at in zip(bodies, (AT_I, AT_J), strict=True)]
    return functions, s_bars


def spring_potential(q, s_bars):
    """1/2 k (l - l0)^2 with l = |x_j - x_i|, in numpy."""
    length = np.linalg.norm(point_position(q, 1, s_bars[1]) - point_position(q, 0, s_bars[0]))
    return 0.5 * STIFFNESS * (length - FREE_LENGTH) ** 2


def test_spring_potential_value(rng):
    functions, s_bars = spring_model(rng)
    _, q, q_dot, *_ = random_state(rng)
    _, potential = functions.evaluate("energy", 0.0, q, q_dot)
    np.testing.assert_allclose(potential.item(), spring_potential(q, s_bars), **EXACT)


def test_spring_force_is_minus_the_potential_gradient(rng):
    """Zero damping: Q = -dV/dq. Checked (a) in every direction of R^14 against the FD gradient
    of the compiled potential, and (b) along physical (tangent) directions against the FD
    derivative of the numpy potential 1/2 k (l - l0)^2."""
    functions, s_bars = spring_model(rng)
    _, q, _, _, _ = random_state(rng)
    q_force = functions.vector("generalized_forces", 0.0, q, np.zeros_like(q))

    def compiled_potential(x):
        return functions.evaluate("energy", 0.0, x, np.zeros_like(x))[1].item()

    h = 1e-5
    gradient = np.array([(compiled_potential(q + h * e) - compiled_potential(q - h * e)) / (2 * h)
                         for e in np.eye(q.size)])
    # Central FD, h = 1e-5, of V up to O(100) (k = 35, |Q| up to ~400): truncation
    # h^2/6 |V'''| plus roundoff eps |V| / h ~ 2e-9; measured max error 6e-8 on entries of
    # O(100), i.e. < 2% of the allowed 1e-7 + 1e-7 |Q|. A wrong Q is off by O(|Q|).
    np.testing.assert_allclose(q_force, -gradient, rtol=1e-7, atol=1e-7)
    for _ in range(3):
        direction = tangent_velocity(rng, q)
        dv = (spring_potential(q + h * direction, s_bars)
              - spring_potential(q - h * direction, s_bars)) / (2 * h)
        np.testing.assert_allclose(q_force @ direction, -dv, rtol=1e-7, atol=1e-7)
