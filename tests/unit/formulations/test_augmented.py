"""The augmented-Lagrangian accelerations and projection (formulations.augmented) against the
saddle-point solve and runtime.assembly.project, on a state off the flat poses."""

import numpy as np
import pytest

import casmech
from casmech.formulations import augmented
from casmech.formulations.table import BODY_FORMS
from casmech.runtime import assembly, dynamics
from tests.integration.runtime.test_stabilization import CHAIN


@pytest.fixture(scope="module")
def chain():
    functions = casmech.compile(casmech.loads(CHAIN))
    q, q_dot = assembly.initial_state(functions, 0.0)
    return functions, q, q_dot


@pytest.mark.parametrize("name", ["rp", "romega"])
def test_accelerations_solve_the_saddle_point_system(chain, name):
    """Where P has full row rank, the iterates converge to the [M P^T; P 0] solution."""
    functions, q, q_dot = chain
    form = BODY_FORMS[name]
    v = dynamics.velocities(functions, name, q, q_dot)
    t = 0.3
    mass, jac = functions.matrix(form.mass, q), functions.matrix(form.jacobian, t, q)
    lhs = np.block([[mass, jac.T], [jac, np.zeros((len(jac), len(jac)))]])
    rhs = np.concatenate([functions.vector(form.forces, t, q, v),
                          functions.vector(form.gamma, t, q, v)])
    exact = np.linalg.solve(lhs, rhs)
    solve = augmented.accelerations(functions.functions, name)
    v_dot, lam = (np.array(out.full()).ravel()
                  for out in solve(t, q, v, dynamics.penalty(functions, form, q)))
    # v_dot: measured 8e-17 and 3e-16 of the largest entry, since every iteration solves for a
    # correction from the residual (the iterates themselves, solved directly, were 4e-8 off:
    # the condition of M + a P^T P is ~ the penalty ratio 1e8, Fallback.penalty)
    want = exact[:len(v)]
    np.testing.assert_allclose(v_dot, want, rtol=0, atol=1e-13 * np.max(np.abs(want)))
    # lam: measured 1e-8 of the largest entry, a (P v_dot - gamma) with a ~ 1e8 times mass
    want = exact[len(v):]
    np.testing.assert_allclose(lam, want, rtol=0, atol=1e-7 * np.max(np.abs(want)))


@pytest.mark.parametrize("name", ["rp", "romega"])
def test_projection_is_assembly_project(chain, name):
    """From a state 1e-6 off the constraints, one call of the graph (two Gauss-Newton steps)
    lands where assembly.project's calls of it until |Phi| <= 1e-12 do, with the constraints
    held."""
    functions, q, q_dot = chain
    form = BODY_FORMS[name]
    rng = np.random.default_rng(3)
    v = dynamics.velocities(functions, name, q, q_dot)
    q_off, v_off = q + 1e-6 * rng.standard_normal(len(q)), v + 1e-6 * rng.standard_normal(len(v))
    a, t = dynamics.penalty(functions, form, q), 0.0
    project = augmented.projection(functions.functions, name)
    q_new, v_new = (np.array(out.full()).ravel() for out in project(t, q_off, v_off, a))
    q_ref, v_ref = assembly.project(functions, form, t, q_off, v_off, a)
    # measured 2.6e-14 (q) and 5.5e-14 / 2.4e-13 (v, rp / romega): the same point, where
    # assembly.project stops at |Phi| <= 1e-12 (the assembly tolerance)
    np.testing.assert_allclose(q_new, q_ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(v_new, v_ref, rtol=0, atol=1e-12)
    assert np.max(np.abs(functions.vector("phi", t, q_new))) <= 1e-12
    jac = functions.matrix(form.jacobian, t, q_new)
    residual = jac @ v_new - functions.vector(form.nu, t, q_new)
    assert np.max(np.abs(residual)) <= 1e-12
    # and it moved the state: the perturbation was not already consistent
    assert np.max(np.abs(q_new - q_off)) > 1e-8
