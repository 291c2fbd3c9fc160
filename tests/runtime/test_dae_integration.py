"""How runtime.dynamics hands the DAE of compiler.dae to IDAS: the shifted problem (one
integrator per output grid, the initial derivative through the shift instead of init_xdot),
against the plain DAE started with init_xdot."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.compiler import dae
from casmech.compiler.formulations import FORMULATIONS
from casmech.runtime import assembly
from casmech.runtime.dynamics import velocities
from tests.conftest import MODELS
from tests.runtime.reference_data import VALIDATION_MODELS


def _state(functions, name):
    """A consistent state of Bricard (closed loop, one redundant row) with some motion."""
    q, q_dot = assembly.initial_state(functions)
    q_dot = assembly.solve_velocities(functions, 0.0, q, q_dot + 0.3)
    return q, velocities(functions, name, q, q_dot)


def _saddle_solution(functions, name, t, q, v, mask):
    """(v_dot, unit-row lam) of [M P^T; P -diag(mask)] by a dense solve in NumPy."""
    form = FORMULATIONS[name]
    jac = functions.matrix(form.jacobian, t, q)
    norms = np.linalg.norm(jac, axis=1)
    jac = jac / norms[:, None]
    gamma = functions.vector(form.gamma, t, q, v) / norms
    mass = functions.matrix(form.mass, q)
    lhs = np.block([[mass, jac.T], [jac, -np.diag(mask)]])
    rhs = np.concatenate([functions.vector(form.forces, t, q, v), gamma])
    z = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    return z[:mass.shape[0]], z[mass.shape[0]:]


@pytest.fixture(scope="module")
def bricard():
    return casmech.compile(casmech.load(MODELS / "bricard.yaml"))


def test_shifted_problem_starts_with_zero_derivative(bricard):
    """y'(0) = 0 at a consistent state, and the algebraic equations are those of x."""
    residual = dae.residual(bricard.functions, "rp")
    problem = dae.shifted_problem(residual)
    q, v = _state(bricard, "rp")
    m = residual.size1_in("p") - 1
    p = np.concatenate([[0.0], np.zeros(m)])
    p[1:] = casmech.runtime.dynamics._Model(bricard, "rp").mask(0.0, q)
    x0 = np.concatenate([q, v])
    z0 = np.concatenate(_saddle_solution(bricard, "rp", 0.0, q, v, p[1:]))
    x_dot0 = residual(t=0.0, x=x0, z=z0, p=p)["ode"].full().ravel()
    f = ca.Function("f", [problem[k] for k in ("t", "x", "z", "p")],
                    [problem["ode"], problem["alg"]])
    ode, alg = (a.full().ravel() for a in f(0.0, x0, z0, np.concatenate([p, x_dot0])))
    np.testing.assert_allclose(ode, 0, rtol=0, atol=1e-14)  # x_dot0 - x_dot0, exactly
    np.testing.assert_allclose(alg, 0, rtol=0, atol=1e-9)  # one dense solve: roundoff


@pytest.mark.parametrize("name", ["rp", "romega"])
def test_shifted_integration_matches_init_xdot_integration(name):
    """IDAS on the shifted problem (x = y + tau x_dot0) and on the plain DAE started with
    init_xdot reach the same states over 0.5 s of the spherical ADAMS pendulum (the
    shift is linear in tau, which BDF integrates exactly; only the error weights differ)."""
    functions = casmech.compile(casmech.load(VALIDATION_MODELS / "spherical_case01.yaml"))
    residual = dae.residual(functions.functions, name)
    q, q_dot = assembly.initial_state(functions)
    v = velocities(functions, name, q, q_dot)
    x0 = np.concatenate([q, v])
    p = np.zeros(residual.size1_in("p"))
    z0 = np.concatenate(_saddle_solution(functions, name, 0.0, q, v, p[1:]))
    x_dot0 = residual(t=0.0, x=x0, z=z0, p=p)["ode"].full().ravel()
    grid = list(np.arange(1, 51) * 0.01)
    options = {"reltol": 1e-11, "abstol": 1e-13, "calc_ic": False, "suppress_algebraic": True}
    plain = ca.integrator("plain", "idas", dae.problem(residual), 0.0, grid,
                          options | {"init_xdot": list(x_dot0)})
    shifted = ca.integrator("shifted", "idas", dae.shifted_problem(residual), 0.0, grid,
                            options)
    want = plain(x0=x0, z0=z0, p=p)["xf"].full()
    got = shifted(x0=x0, z0=z0, p=np.concatenate([p, x_dot0]))["xf"].full()
    got += np.outer(x_dot0, grid)
    # each run's own error at rtol 1e-11 over 0.5 s: measured apart by 8.6e-11 (rp), 7.7e-10
    # (romega) on states up to ~4
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-8)
