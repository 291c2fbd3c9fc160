"""optimal/dae: the initial state x0(theta) goes through the runtime's assembly rootfinder, so
its derivative is the implicit one of the closest point; checked against central differences
of the runtime assembly of re-loaded models."""

import casadi as ca
import numpy as np

import casmech
from casmech.optimal.dae import build_dae, initial_state_function
from casmech.optimal.system import parametric_system
from casmech.runtime import assembly
from tests.integration.optimal.test_sensitivity import FOUR_BAR


def assembled(cx: float) -> np.ndarray:
    functions = casmech.compile(casmech.loads(FOUR_BAR, overrides={"cx": repr(cx)}))
    return assembly.assemble_positions(functions)


def test_initial_positions_and_their_derivative_against_central_differences():
    """The four-bar of test_sensitivity (1 DOF): moving cx opens the loop at the file's pose,
    and assembly (the closest point) moves crank and rocker."""
    model = casmech.loads(FOUR_BAR)
    system = parametric_system(model, ["cx"])
    dae = build_dae(system)
    x0 = initial_state_function(dae)
    theta = ca.MX.sym("theta", 1)
    q0 = x0(theta)[:dae.n]
    both = ca.Function("both", [theta], [q0, ca.jacobian(q0, theta)])
    value, derivative = (np.array(v).ravel() for v in both(system.values))
    cx = float(system.values[0])
    # the same rootfinder from the same start as the runtime: roundoff
    np.testing.assert_allclose(value, assembled(cx), rtol=0, atol=1e-12)
    h = 1e-3
    fd = (8 * (assembled(cx + h) - assembled(cx - h))
          - (assembled(cx + 2 * h) - assembled(cx - 2 * h))) / (12 * h)
    # 4th-order differences: h^4 truncation ~1e-12, assembly roundoff 1e-15 / h ~1e-12
    np.testing.assert_allclose(derivative, fd, rtol=0, atol=1e-10)
    assert np.max(np.abs(derivative)) > 0.05  # the pose does move with cx
