"""The joint formulation's equations for optimal control (Formulation.controlled,
formulations/joint_control.py), over model.parametric.split's IR and data, checked against
the body coordinates: the assembled r-p state (runtime.assembly, Newton on Phi), the r-p mass
matrix, and the rp formulation's consistent start (a second formulation of the same motion).
The other formulations do not offer them: a UsageError naming the one that does."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.errors import UsageError
from casmech.formulations.registry import FORMULATIONS
from casmech.model import parametric
from casmech.model.lower import lower
from casmech.runtime import assembly
from tests.conftest import MODELS


def controlled(name: str):
    """(ControlEquations, the model data at the file's values, the compiled functions,
    (q0, q_dot0) the assembled r-p state) of models/<name>.yaml."""
    model = casmech.load(MODELS / f"{name}.yaml")
    split = parametric.split(lower(model))
    functions = casmech.compile(model)
    equations = FORMULATIONS["joint"].controlled(split.ir, split.symbols)
    return equations, ca.DM(split.values), functions, assembly.initial_state(functions, 0.0)


@pytest.fixture(scope="module")
def double_pendulum():
    return controlled("double_pendulum")


@pytest.fixture(scope="module")
def four_bar():
    return controlled("four_bar_released")


@pytest.mark.parametrize("name", ["rp", "romega"])
def test_body_formulations_do_not_offer_them(name):
    split = parametric.split(lower(casmech.load(MODELS / "pendulum.yaml")))
    with pytest.raises(UsageError) as error:
        FORMULATIONS[name].controlled(split.ir, split.symbols)
    message = str(error.value)
    assert message.startswith(f"the {name} formulation does not offer the equations optimal "
                              "control takes")
    assert "FORMULATIONS['joint']" in message and "formulation: bodies" in message


@pytest.mark.parametrize("case", ["double_pendulum", "four_bar"])
def test_state_and_body_coordinates_are_inverse(case, request):
    """x from the assembled r-p state, taken back to body coordinates by the tree's
    kinematics, is that state (Euler parameters with the signs that continue them)."""
    equations, d, _, (q0, q_dot0) = request.getfixturevalue(case)
    x0 = equations.state(q0, q_dot0, d)
    keep = equations.independent(0.0, x0, d)
    signs = equations.signs(0.0, x0, q0, d)
    z = equations.multipliers(ca.DM(0.0), ca.DM(x0), d, np.flatnonzero(keep))
    q, q_dot = (np.array(ca.DM(v)).ravel() for v in equations.body(0.0, x0, z, signs, d)[:2])
    # two routes to the same pose: the tree's recursion and assembly's Newton (to 1e-12)
    np.testing.assert_allclose(q, q0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(q_dot, q_dot0, rtol=0, atol=1e-10)


def test_forced_adds_the_efforts_through_the_joint_mass_matrix(double_pendulum, rng):
    """forced(tau) - forced(0) = M_joint^-1 tau on x's velocities, M_joint = J^T M_rp J from
    the r-p mass matrix and J = d q_dot / d u of the tree (kinetic energy in both
    coordinates); forced(0) is the unforced ODE."""
    equations, d, functions, _ = double_pendulum
    n_theta, n_x = equations.n_coordinates, equations.n_x
    t, x = ca.SX.sym("t"), ca.SX.sym("x", n_x)
    q, q_dot = equations.body(t, x, ca.SX(0, 1), ca.DM.ones(functions.n_bodies), d)[:2]
    kinematics = ca.Function("k", [t, x], [q, ca.jacobian(q_dot, x[n_theta:])])
    for _ in range(3):
        state = rng.uniform(-1.5, 1.5, n_x)
        tau = rng.uniform(-2, 2, n_x - n_theta)
        free = np.array(ca.DM(equations.forced(0.3, state, np.zeros(n_x - n_theta), d))).ravel()
        pushed = np.array(ca.DM(equations.forced(0.3, state, tau, d))).ravel()
        own = np.array(ca.DM(equations.ode(0.3, state, d))).ravel()
        pose, jacobian = (np.array(v.full()) for v in kinematics(0.3, state))
        mass = jacobian.T @ np.array(functions["mass_matrix"](pose.ravel()).full()) @ jacobian
        # the same equations evaluated twice (roundoff)
        np.testing.assert_allclose(free, own, rtol=0, atol=1e-12)
        # ABA against the r-p mass matrix: two formulations of the inertia, to roundoff of
        # O(1) kg m^2 entries
        np.testing.assert_allclose(mass @ (pushed - free)[n_theta:], tau, rtol=0, atol=1e-10)
        np.testing.assert_allclose((pushed - free)[:n_theta], 0, rtol=0, atol=0)  # exact


def test_forced_is_a_tree_s(four_bar):
    equations, d, _, _ = four_bar
    with pytest.raises(UsageError, match="for a tree only; this model has loop closures"):
        equations.forced(0.0, np.zeros(equations.n_x), np.zeros(1), d)


def test_loops_closure_and_multipliers_against_rp(four_bar):
    """At the assembled state the closure rows vanish and a unit quaternion's norm is one,
    away from it they do not; the accelerations with the kept rows' multipliers are the rp
    formulation's consistent ones (its saddle solve of the same start)."""
    equations, d, functions, (q0, q_dot0) = four_bar
    assert equations.n_cut > 0
    x0 = equations.state(q0, q_dot0, d)
    keep = equations.independent(0.0, x0, d)
    # the spatial four-bar (spherical, universal) has no redundant rows: every one kept
    np.testing.assert_array_equal(keep, np.ones(equations.n_cut))
    positions, velocities = (np.array(ca.DM(v)).ravel() for v in equations.closure(0.0, x0, d))
    # assembly's Newton solves Phi = 0 and projects the velocities to 1e-12
    np.testing.assert_allclose(positions, 0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(velocities, 0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.array(ca.DM(equations.invariants(x0))), 0, rtol=0,
                               atol=1e-12)  # unit quaternions from the rotation matrices
    moved = x0 + 0.1
    assert np.max(np.abs(np.array(ca.DM(equations.closure(0.0, moved, d)[0])))) > 1e-3
    z = equations.multipliers(ca.DM(0.0), ca.DM(x0), d, np.flatnonzero(keep))
    signs = equations.signs(0.0, x0, q0, d)
    q_ddot = np.array(ca.DM(equations.body(0.0, x0, z, signs, d)[2])).ravel()
    rp = FORMULATIONS["rp"]
    start = rp.start(functions, rp.system(functions), 0.0, q0, q_dot0)
    reference = start.z[:len(q0)]
    # two formulations' accelerations from the same state, each a direct solve (1e-12 of
    # accelerations of O(10) m/s^2)
    np.testing.assert_allclose(q_ddot, reference, rtol=0, atol=1e-9)


def test_periodic_coordinates_are_the_angles():
    equations = controlled("cart_pole")[0]
    assert equations.n_x == 4  # the cart's displacement and the pole's angle, their rates
    assert equations.periodic() == [1]  # the hinge's angle, not the track's displacement
