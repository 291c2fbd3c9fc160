"""The AD-derived constraint system (equations/assemble.py via functions.build_functions).

A hand-built model of two free bodies with time-dependent basic constraints (to and from ground
too) and driven composite joints. Oracles: finite differences in time along arbitrary smooth
trajectories (for gamma and nu), the lecture's closed forms (for Pi_bar), and the definition of
Pi_bar as the coefficient of omega_bar in Phi_dot.
"""

import numpy as np
import pytest

from tests.helpers import oracles
from tests.helpers.equations import (
    axis_angle_p,
    compile_model,
    g_matrix,
    joint,
    model,
    quat_product,
    random_unit_p,
    scalar,
    stack_q,
    two_free_bodies,
    unit,
)

GROUND_POSE = (np.zeros(3), np.array([1.0, 0, 0, 0]))
TIMES = [0.0, 0.37, 1.2]


def build(rng: np.random.Generator):
    """Two free bodies; every primitive kind, with f(t), and with ground on either side."""
    b1, b2 = two_free_bodies(rng)

    def vec():
        return rng.normal(size=3)

    joints = [
        joint("j_dp1", "dp1", "b1", "b2", a_i=vec(), a_j=vec(), f=scalar("0.3*sin(2*t)")),
        joint("j_dp2", "dp2", "ground", "b1", a_i=vec(), s_i=vec(), s_j=vec(),
              f=scalar("0.2*t**2 - 0.1")),
        joint("j_d", "d", "b1", "b2", s_i=vec(), s_j=vec(), f=scalar("1.5 + 0.4*cos(3*t)")),
        joint("j_cd", "cd", "b2", "ground", c=vec(), s_i=vec(), s_j=vec(),
              f=scalar("0.3*sin(2*t)")),
        joint("hinge", "revolute", "b1", "b2", at=[0.9, 0.1, 0.7], axis=unit(vec()),
              driver_angle=scalar("0.5*t + 0.2*sin(3*t)")),
        joint("slider", "translational", "ground", "b2", at=[1.0, 0.5, 0.4], axis=unit(vec()),
              driver_displacement=scalar("0.1*t**3 + 0.05*exp(t)")),
    ]
    return compile_model(model([b1, b2], joints))


@pytest.fixture
def system(rng):
    return build(rng)


class Trajectory:
    """q(t) = q0 + a sin(w t + phase) + b t^2 per coordinate: smooth, arbitrary, NOT on the
    constraint manifold (and p not unit): gamma's identity holds for any trajectory. q0 is a
    pose of unit-size numbers so that |Phi| stays O(10) and the FD roundoff small."""

    def __init__(self, rng: np.random.Generator, n_bodies: int):
        n = 7 * n_bodies
        poses = [(rng.normal(size=3), random_unit_p(rng)) for _ in range(n_bodies)]
        self.q0 = stack_q(poses)
        self.a, self.w = 0.3 * rng.normal(size=n), rng.uniform(0.5, 2.0, size=n)
        self.phase, self.b = rng.uniform(0, 2 * np.pi, size=n), 0.1 * rng.normal(size=n)

    def q(self, t):
        return self.q0 + self.a * np.sin(self.w * t + self.phase) + self.b * t**2

    def q_dot(self, t):
        return self.a * self.w * np.cos(self.w * t + self.phase) + 2 * self.b * t

    def q_ddot(self, t):
        return -self.a * self.w**2 * np.sin(self.w * t + self.phase) + 2 * self.b


def phi_along(system, path, t):
    return system.vector("phi", t, path.q(t))


@pytest.mark.parametrize("t", TIMES)
def test_gamma_by_finite_differences(system, rng, t):
    """d^2/dt^2 Phi(q(t), t) = Phi_q q_ddot - gamma(t, q, q_dot) (the acceleration equation's
    right-hand side), with the second derivative by central differences, h = 1e-4."""
    path = Trajectory(rng, system.n_bodies)
    h = 1e-4
    fd = (phi_along(system, path, t + h) - 2 * phi_along(system, path, t)
          + phi_along(system, path, t - h)) / h**2
    q, q_dot = path.q(t), path.q_dot(t)
    exact = (system.matrix("phi_q", t, q) @ path.q_ddot(t)
             - system.vector("gamma", t, q, q_dot))
    # Measured on this model (5 seeds x 3 times): max |error| 1e-4 at h = 1e-3 (truncation,
    # scales as h^2 -> 1e-6 at h = 1e-4) and 2.2e-6 at h = 1e-4, where roundoff
    # 4 eps |Phi| / h^2 (<= 7e-6 for |Phi| <= 80) dominates. atol 2e-5 is ~10x the measured
    # error; rtol is kept negligible (1e-7 * |d2Phi| <= 1e-5). A wrong gamma term is O(1).
    np.testing.assert_allclose(exact, fd, rtol=1e-7, atol=2e-5)


@pytest.mark.parametrize("t", TIMES)
def test_nu_by_finite_differences(system, rng, t):
    """nu = -dPhi/dt at fixed q (central differences, h = 1e-5)."""
    q = Trajectory(rng, system.n_bodies).q(0.0)
    h = 1e-5
    fd = (system.vector("phi", t + h, q) - system.vector("phi", t - h, q)) / (2 * h)
    # Truncation h^2/6 |Phi_ttt| ~ 1e-10 * 30, roundoff eps |Phi| / h ~ 1e-9 for |Phi| ~ 80;
    # measured max 2.3e-10 (5 seeds x 3 times). 1e-8 covers both with margin.
    np.testing.assert_allclose(system.vector("nu", t, q), -fd, rtol=1e-8, atol=1e-8)


def unit_configuration(system, rng):
    """q with unit Euler parameters (Pi_bar = 1/2 Phi_p G^T is the variation only there)."""
    poses = [(rng.normal(size=3), random_unit_p(rng)) for _ in range(system.n_bodies)]
    return poses, stack_q(poses)


def split(system, q):
    nb = system.n_bodies
    return q[: 3 * nb], [q[3 * nb + 4 * k: 3 * nb + 4 * k + 4] for k in range(nb)]


@pytest.mark.parametrize("t", TIMES)
def test_pi_bar_is_half_phi_p_g_transpose(system, rng, t):
    _, q = unit_configuration(system, rng)
    phi_r, pi_bar = system.evaluate("variations", t, q)
    phi_q = system.matrix("phi_q", t, q)
    nb = system.n_bodies
    _, ps = split(system, q)
    expected = np.hstack([0.5 * phi_q[:, 3 * nb + 4 * k: 3 * nb + 4 * k + 4] @ g_matrix(ps[k]).T
                          for k in range(nb)])
    # Roundoff of O(10) flops on entries of O(10).
    np.testing.assert_allclose(pi_bar, expected, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(phi_r, phi_q[:, : 3 * nb], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("t", TIMES)
def test_variations_match_the_lecture_row_by_row(system, rng, t):
    """Every joint row's [Phi_r, Pi_bar] equals the lecture's delta-pi_bar closed form of its
    primitive (ground rows: only the body's columns); normalization rows have Pi_bar = 0."""
    poses, q = unit_configuration(system, rng)
    phi_r, pi_bar = system.evaluate("variations", t, q)
    expected_r, expected_pi = np.zeros_like(phi_r), np.zeros_like(pi_bar)
    for row, prim in enumerate(system.ir.primitives):
        pose_i = GROUND_POSE if prim.body_i < 0 else poses[prim.body_i]
        pose_j = GROUND_POSE if prim.body_j < 0 else poses[prim.body_j]
        pair = oracles.Pair(*pose_i, *pose_j, prim.vectors)
        if prim.kind == "angle":
            blocks = oracles.angle_pi(pair, prim.f.value(t=t))
        else:
            blocks = oracles.DELTA_PI[prim.kind](pair)
        for body_index, r_block, pi_block in ((prim.body_i, 0, 1), (prim.body_j, 2, 3)):
            if body_index >= 0:
                columns = slice(3 * body_index, 3 * body_index + 3)
                expected_r[row, columns] += blocks[r_block]
                expected_pi[row, columns] += blocks[pi_block]
    assert len(system.ir.primitives) == system.n_rows - system.n_bodies
    # Roundoff of O(100) flops on entries of O(10).
    np.testing.assert_allclose(phi_r, expected_r, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(pi_bar, expected_pi, rtol=1e-12, atol=1e-12)


def flavours(system, rng):
    """A configuration with unit p and a velocity with p_dot = 1/2 G^T omega_bar."""
    poses, q = unit_configuration(system, rng)
    r_dot = rng.normal(size=3 * system.n_bodies)
    omega_bar = rng.normal(size=3 * system.n_bodies)
    p_dot = [0.5 * g_matrix(p).T @ omega_bar[3 * k: 3 * k + 3] for k, (_, p) in enumerate(poses)]
    return poses, q, r_dot, omega_bar, np.concatenate([r_dot, *p_dot])


@pytest.mark.parametrize("t", TIMES)
def test_the_two_flavours_of_the_variation_agree(system, rng, t):
    """Phi_q q_dot (delta-p flavour) == Phi_r r_dot + Pi_bar omega_bar (delta-pi_bar flavour)."""
    _, q, r_dot, omega_bar, q_dot = flavours(system, rng)
    phi_r, pi_bar = system.evaluate("variations", t, q)
    # Roundoff of O(100) flops on entries of O(10).
    np.testing.assert_allclose(system.matrix("phi_q", t, q) @ q_dot,
                               phi_r @ r_dot + pi_bar @ omega_bar, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("t", TIMES)
def test_pi_bar_is_the_coefficient_of_omega_bar_in_phi_dot(system, rng, t):
    """Independent of G: move every body rigidly, r(s) = r + s r_dot, A(s) = A exp(s omega_bar~)
    (constant body-frame angular velocity), and differentiate Phi(q(s), t + s) by central
    differences: Phi_dot = Phi_r r_dot + Pi_bar omega_bar - nu."""
    poses, q, r_dot, omega_bar, _ = flavours(system, rng)

    def q_at(s):
        moved = []
        for k, (r, p) in enumerate(poses):
            w = omega_bar[3 * k: 3 * k + 3]
            turn = axis_angle_p(w, s * np.linalg.norm(w))
            moved.append((r + s * r_dot[3 * k: 3 * k + 3], quat_product(p, turn)))
        return stack_q(moved)

    h = 1e-5
    fd = (system.vector("phi", t + h, q_at(h)) - system.vector("phi", t - h, q_at(-h))) / (2 * h)
    phi_r, pi_bar = system.evaluate("variations", t, q)
    exact = phi_r @ r_dot + pi_bar @ omega_bar - system.vector("nu", t, q)
    # Truncation h^2/6 |Phi'''| (measured: 6e-7 at h = 1e-4, 6e-9 at h = 1e-5, i.e. h^2),
    # roundoff eps |Phi| / h ~ 1e-9: 1e-7 is 15x the measured error; a wrong Pi_bar is O(1).
    np.testing.assert_allclose(exact, fd, rtol=1e-7, atol=1e-7)
