"""Joints' `initial:` values in casmech.optimal: exact derivatives of results columns with
respect to a parameter written in an initial value (and the geometry the loop closes with),
against central differences of separate runs; optimal control's initial state is the runtime's
assembly with the values held."""

import numpy as np

import casmech
from casmech.optimal.dae import build_dae, initial_state_function
from casmech.optimal.sensitivity import sensitivity, simulate
from casmech.optimal.system import parametric_system
from casmech.runtime.assembly import initial_state
from tests.validation.runtime.test_initial_state import four_bar

OUTPUTS = ["crank.x", "coupler.vy", "rocker_pivot.angle", "coupler_pin.e3"]
TIMES = [0.01, 0.3]


def test_derivatives_through_the_held_initial_values_are_the_central_differences():
    text = four_bar()
    model = casmech.loads(text)
    found = sensitivity(model, ["A", "W", "c"], OUTPUTS, TIMES)
    step = 1e-4
    for k, name in enumerate(("A", "W", "c")):
        value = float(model.parameters[name])
        plus = simulate(casmech.loads(text, overrides={name: repr(value + step)}), OUTPUTS, TIMES)
        minus = simulate(casmech.loads(text, overrides={name: repr(value - step)}), OUTPUTS,
                         TIMES)
        # central difference: O(h^2) ~ 1e-8, plus IDAS's rtol 1e-10 over 2h: ~1e-6
        np.testing.assert_allclose(found.jacobian[:, :, k], (plus - minus) / (2 * step),
                                   rtol=1e-5, atol=1e-6)


def test_the_optimal_initial_state_is_the_assembly_with_the_values_held():
    model = casmech.loads(four_bar())
    dae = build_dae(parametric_system(model, ["A"]))
    x0 = np.array(initial_state_function(dae)(np.array([0.5]))).ravel()
    q, q_dot = initial_state(casmech.compile(model))
    np.testing.assert_allclose(x0, np.concatenate([q, q_dot]), rtol=0,
                               atol=1e-12)  # two solvers of the same KKT conditions
