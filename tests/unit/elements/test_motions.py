"""Tree-joint motions (elements/motions.py, joint_types.MOTIONS) against FD and inverses."""

import casadi as ca
import numpy as np
import pytest

from casmech.core import euler, spatial
from casmech.core.quaternions import from_matrix
from casmech.elements.joint_types import MOTIONS
from casmech.formulations.articulated import local_motion

RNG = np.random.default_rng(7)


def random_theta(kind: str) -> np.ndarray:
    motion = MOTIONS[kind]
    theta = RNG.uniform(-1.2, 1.2, motion.n_q)
    for start in motion.quaternions:
        theta[start:start + 4] /= np.linalg.norm(theta[start:start + 4])
    return theta


def pose(kind: str, theta) -> tuple[np.ndarray, np.ndarray]:
    """(rotation matrix of F_c in F_p, F_c's origin in F_p) at theta."""
    rotation, translation = local_motion(kind)(theta, np.zeros(MOTIONS[kind].n_v))[:2]
    return (euler.numeric(euler.rotation, np.array(rotation.full()).ravel()),
            np.array(translation.full()).ravel())


@pytest.mark.parametrize("kind", sorted(MOTIONS))
def test_coordinates_invert_the_motion(kind):
    for _ in range(5):
        theta = random_theta(kind)
        back = MOTIONS[kind].coordinates(*pose(kind, theta))
        if MOTIONS[kind].quaternions:  # q and -q are one rotation: compare up to sign
            back[0:4] *= np.sign(back[0:4] @ theta[0:4])
        # the inverse is closed form (atan2, Shepperd): roundoff only
        np.testing.assert_allclose(back, theta, rtol=0, atol=1e-12)


@pytest.mark.parametrize("kind", sorted(MOTIONS))
def test_subspace_gives_the_twist_of_the_finite_differenced_pose(kind):
    """S u against central differences of the pose along theta_dot(theta, u): angular velocity
    from R^T R_dot, origin velocity from d_dot, both in F_c coordinates."""
    motion, h = MOTIONS[kind], 1e-6
    for _ in range(3):
        theta, u = random_theta(kind), RNG.uniform(-2, 2, motion.n_v)
        out = local_motion(kind)(theta, u)
        subspace, theta_dot = np.array(out[2].full()), np.array(out[4].full()).ravel()
        (r_plus, d_plus), (r_minus, d_minus) = (pose(kind, theta + s * h * theta_dot)
                                                for s in (1, -1))
        rotation, _ = pose(kind, theta)
        w = rotation.T @ (r_plus - r_minus) / (2 * h)
        omega = np.array([w[2, 1], w[0, 2], w[1, 0]])
        velocity = rotation.T @ (d_plus - d_minus) / (2 * h)
        # central differences with h = 1e-6 on O(1) maps: truncation ~1e-12, roundoff ~1e-10
        np.testing.assert_allclose(subspace @ u, np.concatenate([omega, velocity]),
                                   rtol=0, atol=1e-8)


def test_subspace_rate_is_the_derivative_of_s_u_along_the_motion():
    """c_J = d/dt (S(theta) u) at constant u, by central differences (the universal joint's
    S depends on its angles)."""
    kind, h = "universal", 1e-6
    theta, u = random_theta(kind), RNG.uniform(-2, 2, 2)
    out = local_motion(kind)(theta, u)
    theta_dot, rate = np.array(out[4].full()).ravel(), np.array(out[3].full()).ravel()
    s_plus, s_minus = (np.array(local_motion(kind)(theta + s * h * theta_dot, u)[2].full())
                       for s in (1, -1))
    # central differences, h = 1e-6: error ~1e-10
    np.testing.assert_allclose(rate, (s_plus - s_minus) @ u / (2 * h), rtol=0, atol=1e-8)


def test_quaternion_rates_keep_the_norm():
    theta, u = ca.SX.sym("theta", 4), ca.SX.sym("u", 3)
    rate = MOTIONS["spherical"].rates(theta, u)
    norm_rate = ca.Function("norm_rate", [theta, u], [theta.T @ rate])
    for _ in range(5):
        value = float(norm_rate(RNG.normal(size=4), RNG.normal(size=3)))
        # d/dt |theta|^2 / 2 = theta^T G(theta)^T u / 2 = 0 for any theta (G theta = 0):
        # roundoff of O(1) products only
        np.testing.assert_allclose(value, 0.0, rtol=0, atol=1e-14)


@pytest.mark.parametrize("angle", [0.0, 0.3, np.pi / 2, np.pi - 1e-9, np.pi])
def test_from_matrix_inverts_the_rotation(angle):
    axis = RNG.normal(size=3)
    axis /= np.linalg.norm(axis)
    p = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])
    back = from_matrix(euler.numeric(euler.rotation, p))
    # Shepperd's branch choice keeps the division well conditioned up to 180 degrees
    np.testing.assert_allclose(back * np.sign(back @ p), p, rtol=0, atol=1e-12)


@pytest.mark.parametrize("kind", sorted(MOTIONS))
def test_rotation_matrix_is_the_quaternion_s(kind):
    """The matrix of cos and sin of the angles (the recursion's) against A(p) of the joint's
    quaternion (the results rows')."""
    for _ in range(5):
        theta = random_theta(kind)
        matrix = local_motion(kind)(theta, np.zeros(MOTIONS[kind].n_v))[5]
        # two closed forms of one rotation of O(1) entries: roundoff only
        np.testing.assert_allclose(np.array(matrix.full()), pose(kind, theta)[0],
                                   rtol=0, atol=1e-14)


@pytest.mark.parametrize("kind", ["revolute", "cylindrical", "translational"])
def test_axis_joints_select_constant_rows(kind):
    """A joint moving along one fixed axis has a constant selecting S and c_J = 0 exactly, so
    the articulated-body algorithm eliminates it blockwise and its graph has no terms of the
    angle there."""
    motion = MOTIONS[kind]
    theta, u = ca.SX.sym("theta", motion.n_q), ca.SX.sym("u", motion.n_v)
    _, _, subspace, rate, _, _ = local_motion(kind)(theta, u)
    assert spatial.selection(subspace) is not None
    assert rate.is_constant() and not np.any(np.array(ca.evalf(rate)))
