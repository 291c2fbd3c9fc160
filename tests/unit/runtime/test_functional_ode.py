"""runtime.functional_ode: CVODES's functional problem of a tree calls the ODE from the
integrator's own MX function and integrates what the wrapped problem integrates."""

from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.runtime import functional_ode
from casmech.runtime.joint_dynamics import joint_system

MODEL = Path(__file__).parents[3] / "models" / "triple_pendulum.yaml"
OPTIONS = {"reltol": 1e-6, "abstol": 1e-8, "linear_multistep_method": "adams",
           "nonlinear_solver_iteration": "functional"}
GRID = list(np.linspace(0.05, 1.0, 20))


@pytest.fixture(scope="module")
def system():
    return joint_system(casmech.compile(casmech.load(MODEL), "interpreted"))


def _callees(integrator: ca.Function) -> list[ca.Function]:
    """The functions the integrator's right-hand side (daeF) calls."""
    dae = integrator.get_function("daeF")
    return [dae.instruction_MX(k).which_function() for k in range(dae.n_instructions())
            if dae.instruction_id(k) == ca.OP_CALL]


def test_the_direct_problem_calls_the_ode_itself_and_integrates_the_same(system):
    direct = ca.integrator("direct", "cvodes", functional_ode.problem(system), 0.0, GRID,
                           OPTIONS)
    wrapped = ca.integrator("wrapped", "cvodes", system.functional_problem, 0.0, GRID, OPTIONS)
    assert system.dynamics.class_name() == "SXFunction"  # interpreted: not an MX wrapper
    (callee,) = _callees(direct)
    assert callee.class_name() == "SXFunction"
    assert callee.n_instructions() == system.dynamics.n_instructions()
    (wrapper,) = _callees(wrapped)  # the wrapper declaring the ODE not differentiable
    assert wrapper.class_name() == "MXFunction"
    # declared not differentiable too: the integrator holds an empty Jacobian
    assert direct.get_function("jacF").sparsity_out(0).nnz() == 0
    x0 = np.linspace(0.1, 0.6, system.layout.n_x)
    got, want = (np.array(f(x0=x0)["xf"]) for f in (direct, wrapped))
    assert np.all(np.isfinite(got))
    # the same ODE on the same states by the same integrator: the same numbers
    np.testing.assert_allclose(got, want, rtol=0, atol=0)


def test_large_odes_and_newton_keep_the_systems_problems(system, monkeypatch):
    assert functional_ode.problem(system, functional=False) is system.problem
    monkeypatch.setattr(functional_ode, "DIRECT_STATES", system.layout.n_x - 1)
    assert functional_ode.problem(system) is system.functional_problem
