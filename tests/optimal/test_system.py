"""The two ways theta enters the system functions (optimal/system.py) give the same functions
and the same derivatives with respect to theta, for parameters both take (masses, an inertia,
gravity, a spring, an initial velocity in the file and an offset of one)."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.errors import UsageError
from casmech.optimal.dae import build_dae, initial_state_function
from casmech.optimal.system import BUNDLE, parametric_system
from tests.optimal.test_sensitivity import MECHANISM

NAMES = ["m2", "J", "g", "k", "c", "w0", "upper.wz", "lower.vx"]


def _value_and_jacobian(function: ca.Function, args, theta):
    symbol = ca.MX.sym if function.is_a("MXFunction") else ca.SX.sym
    inputs = [symbol(function.name_in(k), function.sparsity_in(k))
              for k in range(function.n_in())]
    outputs = function.call(inputs)
    jacobians = [ca.jacobian(o, inputs[-1]) for o in outputs]
    both = ca.Function("both", inputs, [*outputs, *jacobians])
    return [np.array(v.full()) for v in both.call([*args, theta])]


def test_same_functions_and_theta_derivatives():
    model = casmech.loads(MECHANISM)
    symbolic, data = (parametric_system(model, NAMES, method) for method in ("symbolic", "data"))
    assert (symbolic.method, data.method) == ("symbolic", "data")
    np.testing.assert_array_equal(symbolic.values, data.values)
    rng = np.random.default_rng(3)
    for name in (*BUNDLE, "file_velocities", "initial_guess"):
        function = symbolic[name]
        args = [rng.standard_normal(function.sparsity_in(k).shape)
                for k in range(function.n_in() - 1)]
        for got, want in zip(_value_and_jacobian(data[name], args, data.values),
                             _value_and_jacobian(function, args, symbolic.values),
                             strict=True):
            # the same formulas, numbers as inputs or constants, dd/dtheta of d linear in
            # theta (round-off of the differences: measured 1e-14): 1e-10 of the largest entry
            scale = 1 + np.abs(want).max(initial=0)
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * scale, err_msg=name)


def test_same_initial_state_derivative():
    """x0(theta) (assembly and velocity projection as a graph) and its Jacobian."""
    model = casmech.loads(MECHANISM)
    results = []
    for method in ("symbolic", "data"):
        system = parametric_system(model, NAMES, method)
        x0 = initial_state_function(build_dae(system))
        results.append(_value_and_jacobian(x0, [], system.values))
    for got, want in zip(*results, strict=True):
        # as above: measured 1e-15 of the largest entry
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * (1 + np.abs(want).max()))


def test_unknown_method():
    with pytest.raises(UsageError, match="method 'numeric' is not one of auto, symbolic, data"):
        parametric_system(casmech.loads(MECHANISM), ["k"], "numeric")
