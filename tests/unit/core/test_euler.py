"""Euler-parameter geometry (core/euler.py) against its defining properties.

Oracles: orthonormality, Rodrigues' formula, the identities of Haug (1989) ch. 6
(A = E G^T, G p = 0, E p = 0, omega_bar = 2 G p_dot, omega = 2 E p_dot), and the definition
B(p, a_bar) = d(A(p) a_bar)/dp checked by finite differences and by CasADi AD.
"""

import casadi as ca
import numpy as np

from casmech.core import euler
from tests.helpers import equations as helpers
from tests.helpers.equations import axis_angle_p, dense, rodrigues, skew, unit

# Roundoff of O(10) flops on O(1) numbers is a few eps ~ 1e-15; 1e-13 leaves a 100x margin.
RTOL = ATOL = 1e-13


def tangent(rng, p):
    """A random p_dot with p^T p_dot = 0 (the velocity of a unit quaternion)."""
    v = rng.normal(size=4)
    return v - (v @ p) * p


def random_p(rng):
    return unit(rng.normal(size=4))


def test_rotation_is_orthonormal_with_unit_determinant(rng):
    a = dense(euler.rotation(random_p(rng)))
    np.testing.assert_allclose(a @ a.T, np.eye(3), rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(a.T @ a, np.eye(3), rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(np.linalg.det(a), 1.0, rtol=RTOL, atol=ATOL)


def test_rotation_matches_rodrigues(rng):
    """A(p) of p = [cos(theta/2), sin(theta/2) k] is the rotation by theta about k."""
    axis, angle = unit(rng.normal(size=3)), rng.uniform(-np.pi, np.pi)
    np.testing.assert_allclose(dense(euler.rotation(axis_angle_p(axis, angle))),
                               rodrigues(axis, angle), rtol=RTOL, atol=ATOL)


def test_a_equals_e_g_transpose(rng):
    p = random_p(rng)
    np.testing.assert_allclose(dense(euler.e_matrix(p)) @ dense(euler.g_matrix(p)).T,
                               dense(euler.rotation(p)), rtol=RTOL, atol=ATOL)


def test_g_and_e_annihilate_p(rng):
    p = random_p(rng)
    np.testing.assert_allclose(dense(euler.g_matrix(p)) @ p, np.zeros(3), rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(dense(euler.e_matrix(p)) @ p, np.zeros(3), rtol=RTOL, atol=ATOL)


def fd_jacobian_of_rotation(p, a_bar, h=1e-6):
    """Central finite differences of p -> A(p) a_bar (geometry/euler.rotation) along e_0..e_3."""
    return np.column_stack([
        (dense(euler.rotation(p + h * e)) - dense(euler.rotation(p - h * e))) @ a_bar / (2 * h)
        for e in np.eye(4)])


def ad_jacobian_of_rotation(p, a_bar):
    p_sym = ca.SX.sym("p", 4)
    jac = ca.Function("jacobian_a", [p_sym], [ca.jacobian(euler.rotation(p_sym) @ a_bar, p_sym)])
    return dense(jac(p))


# The next two tests FAIL against the current euler.rotation (reported bug). B(p, a_bar) is the
# Jacobian of the HOMOGENEOUS form A(p) = E G^T = (e0^2 - e^T e) I + 2 e e^T + 2 e0 e~ (Haug,
# lecture). euler.rotation uses 2[(e0^2 - 1/2) I + e e^T + e0 e~], which equals it only on
# p^T p = 1: the difference is (p^T p - 1) I, whose p-derivative is 2 a_bar p^T, so AD of
# euler.rotation gives B(p, a_bar) + 2 a_bar p^T even at unit p (wrong in the radial direction).

def test_b_is_the_finite_difference_jacobian_of_a_times_a_bar(rng):
    p, a_bar = random_p(rng), rng.normal(size=3)
    # A(p) a_bar is quadratic in p, so the central difference has NO truncation error; what is
    # left is roundoff eps * |A a_bar| / h ~ 2e-16 * 3 / 1e-6 ~ 1e-9 (1e-8 covers it).
    np.testing.assert_allclose(dense(euler.b_matrix(p, a_bar)), fd_jacobian_of_rotation(p, a_bar),
                               rtol=1e-8, atol=1e-8)


def test_b_is_the_casadi_jacobian_of_a_times_a_bar(rng):
    p, a_bar = random_p(rng), rng.normal(size=3)
    np.testing.assert_allclose(dense(euler.b_matrix(p, a_bar)), ad_jacobian_of_rotation(p, a_bar),
                               rtol=RTOL, atol=ATOL)


def test_b_is_the_jacobian_along_tangent_directions(rng):
    """The weaker statement that holds for both forms of A: B dp = (A a_bar)_p dp, p^T dp = 0."""
    p, a_bar = random_p(rng), rng.normal(size=3)
    dp = tangent(rng, p)
    b = dense(euler.b_matrix(p, a_bar))
    np.testing.assert_allclose(b @ dp, ad_jacobian_of_rotation(p, a_bar) @ dp,
                               rtol=RTOL, atol=ATOL)
    # FD: roundoff only (quadratic map), as above.
    np.testing.assert_allclose(b @ dp, fd_jacobian_of_rotation(p, a_bar) @ dp,
                               rtol=1e-8, atol=1e-8)


def test_angular_velocity_from_p_dot(rng):
    """omega_bar~ = A^T A_dot and omega~ = A_dot A^T (definitions), with A_dot by central FD of
    A(p + h p_dot), equal 2 G p_dot and 2 E p_dot; and omega = A omega_bar."""
    p = random_p(rng)
    p_dot = tangent(rng, p)
    a = dense(euler.rotation(p))
    h = 1e-6
    a_dot = (dense(euler.rotation(p + h * p_dot)) - dense(euler.rotation(p - h * p_dot))) / (2 * h)
    omega_bar = 2 * dense(euler.g_matrix(p)) @ p_dot
    omega = 2 * dense(euler.e_matrix(p)) @ p_dot
    # A is quadratic in p: no truncation error; roundoff eps / h ~ 2e-10 per entry of A_dot.
    np.testing.assert_allclose(skew(omega_bar.ravel()), a.T @ a_dot, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(skew(omega.ravel()), a_dot @ a.T, rtol=1e-8, atol=1e-8)
    # Exact algebra (A = E G^T, G^T G = I - p p^T): roundoff only.
    np.testing.assert_allclose(a @ omega_bar, omega, rtol=RTOL, atol=ATOL)


def test_p_dot_from_omega_bar(rng):
    """p_dot = 1/2 G^T omega_bar inverts omega_bar = 2 G p_dot on the tangent space."""
    p = random_p(rng)
    p_dot = tangent(rng, p)
    g = dense(euler.g_matrix(p))
    np.testing.assert_allclose(0.5 * g.T @ (2 * g @ p_dot), p_dot, rtol=RTOL, atol=ATOL)


def test_skew_is_the_cross_product(rng):
    a, b = rng.normal(size=3), rng.normal(size=3)
    s = dense(euler.skew(a))
    np.testing.assert_allclose(s @ b, np.cross(a, b), rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(s.T, -s, rtol=RTOL, atol=ATOL)


def test_symbolic_inputs_stay_symbolic():
    p = ca.SX.sym("p", 4)
    assert isinstance(euler.rotation(p), ca.SX)
    assert euler.b_matrix(p, [1.0, 2.0, 3.0]).shape == (3, 4)
    assert euler.g_matrix(p).shape == euler.e_matrix(p).shape == (3, 4)


def test_numpy_oracles_of_the_other_test_files(rng):
    """helpers.rotation / b_matrix / g_matrix / e_matrix (numpy, used to write the lecture's
    closed forms) agree with Rodrigues' formula and with finite differences, independently of
    core/euler.py."""
    axis, angle = unit(rng.normal(size=3)), rng.uniform(-np.pi, np.pi)
    p, a_bar = axis_angle_p(axis, angle), rng.normal(size=3)
    np.testing.assert_allclose(helpers.rotation(p), rodrigues(axis, angle), rtol=RTOL, atol=ATOL)
    h = 1e-6
    fd = np.column_stack([(helpers.rotation(p + h * e) - helpers.rotation(p - h * e)) @ a_bar
                          / (2 * h) for e in np.eye(4)])
    # Quadratic in p: roundoff-only central difference, ~1e-9.
    np.testing.assert_allclose(helpers.b_matrix(p, a_bar), fd, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(helpers.e_matrix(p) @ helpers.g_matrix(p).T, helpers.rotation(p),
                               rtol=RTOL, atol=ATOL)


def test_numeric_columns_equals_numeric_per_column(rng):
    """euler.numeric_columns (one mapped call) = euler.numeric column by column."""
    p = rng.normal(size=(4, 5))
    p /= np.linalg.norm(p, axis=0)
    columns = euler.numeric_columns(euler.e_matrix, p)
    for k in range(5):
        # the same SX evaluated twice: identical up to rounding
        np.testing.assert_allclose(columns[:, 4 * k:4 * k + 4],
                                   euler.numeric(euler.e_matrix, p[:, k]), rtol=0, atol=1e-15)
