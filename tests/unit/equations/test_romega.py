"""r-omega (Newton-Euler) system functions (equations/romega.py via functions.build_functions).

Oracles: the r-p functions of the same model (cross-formulation agreement: velocity and
acceleration constraints, accelerations and multipliers of the augmented systems, kinetic
energy), the quaternion kinematics p_dot = 1/2 p * (0, omega_bar) integrated in closed form with a
central finite difference in time, Euler's rigid-body equations and A^T n for applied torques,
all written in numpy (tests/helpers/equations.py).
"""

from functools import cache

import numpy as np
import pytest

import casmech
from tests.conftest import MODELS
from tests.helpers.equations import g_matrix, quat_product, random_unit_p, rotation, skew, unit

ALL_MODELS = ["slider_crank.yaml", "four_bar.yaml", "me751_pendulum.yaml",
              *sorted(f"validation/{p.name}" for p in (MODELS / "validation").glob("*.yaml"))]
# DOF > 0 (and one driven, DOF 0, for the time-dependent gamma), joints of several kinds, springs
# and dampers (whose forces depend on q_dot), a free body with applied forces.
DYNAMIC_MODELS = ["validation/iftomm_a02_four_bar_N2.yaml", "validation/spherical_case01.yaml",
                  "validation/rotspring_case01.yaml", "validation/transpring_case01.yaml",
                  "validation/universal_case01.yaml", "me751_pendulum.yaml", "free_body"]

# A free body with an asymmetric full inertia tensor under gravity, a point force off the CM and
# torques given in the global and in the body frame.
FREE_BODY = """
casmech: 1
name: free_body
gravity: [0, 0, -9.81]
bodies:
  - name: body
    mass: 2.5
    inertia: [1.0, 2.0, 2.5, 0.1, -0.2, 0.3]
    position: [0.5, -0.3, 1.2]
forces:
  - {name: push, type: force, body: body, at: [0.9, 0.1, 1.0], value: [1, -2, "3*t"]}
  - {name: twist, type: torque, body: body, value: [0.5, "cos(t)", -1.5], frame: global}
  - {name: spin, type: torque, body: body, value: [-0.7, 0.2, "t"], frame: body}
"""

# Identities between functions of one model evaluated in double precision: O(1e3) flops on
# entries of O(1-100); the absolute part covers entries that cancel to zero.
EXACT = {"rtol": 1e-10, "atol": 1e-10}
# Two augmented systems (condition numbers up to ~1e6 here) solved by LU and compared.
SOLVE = {"rtol": 1e-8, "atol": 1e-8}


@cache
def compiled(name: str):
    model = casmech.loads(FREE_BODY) if name == "free_body" else casmech.load(MODELS / name)
    return casmech.compile(model)


def random_state(functions, rng):
    """(t, q, v): CMs near the file's, random unit p, random r_dot and omega_bar."""
    bodies = functions.ir.bodies
    r = np.concatenate([b.r0 + 0.2 * rng.normal(size=3) for b in bodies])
    p = np.concatenate([random_unit_p(rng) for _ in bodies])
    return rng.uniform(0.0, 2.0), np.r_[r, p], rng.normal(size=6 * len(bodies))


def perturbed_state(functions, rng):
    """(t, q, v) near the file's (assembled) pose, where the Jacobians are well conditioned."""
    bodies = functions.ir.bodies
    r = np.concatenate([b.r0 + 0.01 * rng.normal(size=3) for b in bodies])
    p = np.concatenate([unit(b.p0 + 0.01 * rng.normal(size=4)) for b in bodies])
    return rng.uniform(0.0, 2.0), np.r_[r, p], rng.normal(size=6 * len(bodies))


def q_dot_numpy(q, v):
    """[r_dot; 1/2 G(p_k)^T omega_bar_k]."""
    nb = len(q) // 7
    p_dot = [0.5 * g_matrix(q[3 * nb + 4 * k:3 * nb + 4 * k + 4]).T @ v[3 * nb + 3 * k:][:3]
             for k in range(nb)]
    return np.concatenate([v[:3 * nb], *p_dot])


def q_ddot_numpy(q, v, v_dot):
    """d/dt [r_dot; 1/2 G(p)^T omega_bar] = [r_ddot; 1/2 G(p_dot)^T w + 1/2 G(p)^T w_dot]."""
    nb = len(q) // 7
    q_dot = q_dot_numpy(q, v)
    parts = [v_dot[:3 * nb]]
    for k in range(nb):
        p, p_dot = (vec[3 * nb + 4 * k:3 * nb + 4 * k + 4] for vec in (q, q_dot))
        w, w_dot = (vec[3 * nb + 3 * k:3 * nb + 3 * k + 3] for vec in (v, v_dot))
        parts.append(0.5 * g_matrix(p_dot).T @ w + 0.5 * g_matrix(p).T @ w_dot)
    return np.concatenate(parts)


def flow(q, v, tau):
    """q(tau) under constant v: r + r_dot tau, p * (cos(|w| tau/2), sin(|w| tau/2) w/|w|)."""
    nb = len(q) // 7
    r = q[:3 * nb] + v[:3 * nb] * tau
    ps = []
    for k in range(nb):
        w = v[3 * nb + 3 * k:3 * nb + 3 * k + 3]
        angle = np.linalg.norm(w) * tau / 2
        step = np.r_[np.cos(angle), np.sin(angle) * w / np.linalg.norm(w)]
        ps.append(quat_product(q[3 * nb + 4 * k:3 * nb + 4 * k + 4], step))
    return np.concatenate([r, *ps])


@pytest.mark.parametrize("name", ALL_MODELS)
def test_velocity_constraint_matches_rp(name, rng):
    """[Phi_r, Pi_bar] v == Phi_q q_dot(q, v) and nu == nu_rp on the joint rows."""
    functions = compiled(name)
    n = functions.n_joint_rows
    assert n == len(functions.ir.primitives)
    t, q, v = random_state(functions, rng)
    q_dot = functions.vector("romega_q_dot", q, v)
    np.testing.assert_allclose(q_dot, q_dot_numpy(q, v), **EXACT)
    jacobian = functions.matrix("romega_jacobian", t, q)
    assert jacobian.shape == (n, 6 * functions.n_bodies)
    np.testing.assert_allclose(jacobian @ v, functions.matrix("phi_q", t, q)[:n] @ q_dot, **EXACT)
    np.testing.assert_allclose(functions.vector("romega_nu", t, q),
                               functions.vector("nu", t, q)[:n], **EXACT)


@pytest.mark.parametrize("name", ALL_MODELS)
def test_gamma_matches_rp_acceleration_constraint(name, rng):
    """Phi_q q_ddot - gamma_rp == [Phi_r, Pi_bar] v_dot - gamma_hat for any v_dot."""
    functions = compiled(name)
    n = functions.n_joint_rows
    t, q, v = random_state(functions, rng)
    v_dot = rng.normal(size=v.size)
    q_dot, q_ddot = (out.ravel() for out in functions.evaluate("romega_to_rp", q, v, v_dot))
    np.testing.assert_allclose(q_dot, q_dot_numpy(q, v), **EXACT)
    np.testing.assert_allclose(q_ddot, q_ddot_numpy(q, v, v_dot), **EXACT)
    rp = (functions.matrix("phi_q", t, q) @ q_ddot - functions.vector("gamma", t, q, q_dot))[:n]
    romega = (functions.matrix("romega_jacobian", t, q) @ v_dot
              - functions.vector("romega_gamma", t, q, v))
    np.testing.assert_allclose(romega, rp, **EXACT)


@pytest.mark.parametrize("name", ALL_MODELS)
def test_gamma_is_the_time_derivative_of_the_velocity_constraint(name, rng):
    """With v_dot = 0, d/dt ([Phi_r, Pi_bar] v - nu) along the exact flow of q == -gamma_hat."""
    functions = compiled(name)
    t, q, v = random_state(functions, rng)

    def residual(tau):
        q_tau = flow(q, v, tau)
        return (functions.matrix("romega_jacobian", t + tau, q_tau) @ v
                - functions.vector("romega_nu", t + tau, q_tau))

    h = 1e-4
    derivative = (residual(h) - residual(-h)) / (2 * h)
    # Central difference: truncation h^2/6 |c'''| ~ 1e-8 * O(100), round-off eps |c| / h ~ 1e-11.
    np.testing.assert_allclose(derivative, -functions.vector("romega_gamma", t, q, v),
                               rtol=1e-6, atol=1e-5)


def solve_augmented(mass, jacobian, rhs_dynamics, rhs_constraints):
    n = jacobian.shape[0]
    matrix = np.block([[mass, jacobian.T], [jacobian, np.zeros((n, n))]])
    assert np.linalg.cond(matrix) < 1e8, "augmented matrix ill-conditioned at the test state"
    solution = np.linalg.solve(matrix, np.r_[rhs_dynamics, rhs_constraints])
    return solution[:mass.shape[0]], solution[mass.shape[0]:]


@pytest.mark.parametrize("name", DYNAMIC_MODELS)
def test_dynamics_match_rp(name, rng):
    """Both augmented systems give the same q_ddot and the same joint multipliers."""
    functions = compiled(name)
    n = functions.n_joint_rows
    t, q, v = perturbed_state(functions, rng)
    q_dot = functions.vector("romega_q_dot", q, v)
    v_dot, lam = solve_augmented(functions.matrix("romega_mass", q),
                                 functions.matrix("romega_jacobian", t, q),
                                 functions.vector("romega_forces", t, q, v),
                                 functions.vector("romega_gamma", t, q, v))
    q_ddot_rp, lam_rp = solve_augmented(functions.matrix("mass_matrix", q),
                                        functions.matrix("phi_q", t, q),
                                        functions.vector("generalized_forces", t, q, q_dot),
                                        functions.vector("gamma", t, q, q_dot))
    q_ddot = functions.evaluate("romega_to_rp", q, v, v_dot)[1].ravel()
    np.testing.assert_allclose(q_ddot, q_ddot_rp, **SOLVE)
    np.testing.assert_allclose(lam, lam_rp[:n], **SOLVE)


def test_free_body_follows_euler_equations(rng):
    """No joints: m r_ddot = F and J w_dot = n_bar - w x J w, n_bar = A^T n + s_bar x A^T F."""
    functions = compiled("free_body")
    t, q, v = random_state(functions, rng)
    (body,) = functions.ir.bodies
    a, w = rotation(q[3:7]), v[3:6]
    force = 2.5 * np.array([0, 0, -9.81]) + [1, -2, 3 * t]
    s_bar = np.array([0.9, 0.1, 1.0]) - body.r0  # identity orientation in the file
    n_bar = a.T @ [0.5, np.cos(t), -1.5] + [-0.7, 0.2, t] + np.cross(s_bar, a.T @ [1, -2, 3 * t])
    expected = np.r_[force, n_bar - skew(w) @ body.inertia @ w]
    np.testing.assert_allclose(functions.vector("romega_forces", t, q, v), expected, **EXACT)
    mass = functions.matrix("romega_mass", q)
    np.testing.assert_allclose(mass[:3, :3], 2.5 * np.eye(3), **EXACT)
    np.testing.assert_allclose(mass[3:, 3:], body.inertia, **EXACT)
    np.testing.assert_allclose(mass[:3, 3:], 0.0, atol=0.0)


def test_torques_are_rotated_into_the_body_frame(rng):
    """A global torque n on a body gives n_bar = A^T n (w = 0, no gravity, no other load)."""
    text = FREE_BODY.replace("[0, 0, -9.81]", "[0, 0, 0]").split("forces:")[0] + (
        "forces:\n  - {name: twist, type: torque, body: body, value: [0.5, 'cos(t)', -1.5]}\n")
    functions = casmech.compile(casmech.loads(text))
    t, q, _ = random_state(functions, rng)
    n_global = np.array([0.5, np.cos(t), -1.5])
    expected = np.r_[np.zeros(3), rotation(q[3:7]).T @ n_global]
    np.testing.assert_allclose(functions.vector("romega_forces", t, q, np.zeros(6)), expected,
                               **EXACT)


@pytest.mark.parametrize("name", [*ALL_MODELS, "free_body"])
def test_kinetic_energy_matches_rp(name, rng):
    """1/2 v^T M_w v == the energy function's kinetic output at q_dot(q, v)."""
    functions = compiled(name)
    t, q, v = random_state(functions, rng)
    q_dot = functions.vector("romega_q_dot", q, v)
    kinetic = functions.evaluate("energy", t, q, q_dot)[0].item()
    np.testing.assert_allclose(0.5 * v @ functions.matrix("romega_mass", q) @ v, kinetic, **EXACT)
