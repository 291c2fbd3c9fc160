"""The loops' ODE and projection (formulations/loop_ode.py) against the joint DAE's own terms.

The ODE's accelerations come from the saddle system (joint_system.saddle_terms); the DAE's
consistent multipliers at a state come independently from its acceleration_system by least
squares (formulations.joint_start.Loops.z), and the DAE's ODE at them must be the loops' ODE.
The projection is checked by what a projection is: on the rows after, unchanged when already
on them, and the velocity correction M-orthogonal to the rows' null space."""

import casadi as ca
import numpy as np
import pytest
import scipy.linalg

import casmech
from casmech.formulations import loop_ode
from casmech.formulations.joint_start import Loops, initial_state
from casmech.formulations.joint_system import build, saddle_terms
from casmech.formulations.tree import spanning_tree
from casmech.runtime import assembly
from tests.conftest import MODELS

RNG = np.random.default_rng(14)


def _loops(name: str):
    """(functions, system, loops, x0, loop ODE) of a gallery model with loops."""
    functions = casmech.compile(casmech.load(MODELS / f"{name}.yaml"))
    system = build(functions.ir, spanning_tree(functions.ir))
    q0, q_dot0 = assembly.initial_state(functions, 0.0)
    x0 = initial_state(system, q0, q_dot0)
    loops = Loops(system, 0.0, x0)
    terms = saddle_terms(functions.ir, system.tree)
    return functions, system, loops, x0, loop_ode.build(terms, system.dynamics,
                                                       system.layout.n_theta, loops.mask)


def _value(out) -> np.ndarray:
    return np.array(ca.DM(out).full()).ravel()


@pytest.fixture(scope="module", params=["four_bar_released", "bricard"])
def model(request):
    return _loops(request.param)


def test_bricard_has_a_masked_row():
    """The overconstrained Bricard loop exercises the row mask (one redundant row)."""
    assert _loops("bricard")[2].mask.sum() == 1


def test_ode_is_the_dae_at_its_consistent_multipliers(model):
    _, system, loops, x0, loop = model
    n_theta = system.layout.n_theta
    states = [x0]
    if not loops.mask.any():  # away from the constraints too (a redundant row is redundant
        states.append(x0 + RNG.uniform(-0.3, 0.3, len(x0)))  # on them only)
    for t, x in zip((0.0, 0.4), states, strict=False):
        expected = _value(system.dynamics(t, x, loops.z(t, x), loops.mask)[0])
        # two linear solves of the same equations (Cholesky of the saddle's blocks and the
        # acceleration residual's least squares), condition <= ~1e3 here: roundoff of 1e-10
        np.testing.assert_allclose(_value(loop.ode(t, x)), expected, rtol=0,
                                   atol=1e-10 * (1 + np.abs(expected).max()))
        np.testing.assert_array_equal(_value(loop.ode(t, x))[:n_theta], expected[:n_theta])
        # the same solve as one graph (a controller's ODE): the DAE's own function, in SX
        consistent = loop_ode.consistent_ode(system.acceleration_system, system.dynamics,
                                             loops.mask)
        np.testing.assert_allclose(_value(consistent(t, x)), expected, rtol=0,
                                   atol=1e-10 * (1 + np.abs(expected).max()))


def _residuals(system, loops, t, x) -> np.ndarray:
    """The DAE's algebraic rows at z = 0: (1 - w) S Phi_c, (1 - w) S d/dt Phi_c."""
    z = np.zeros(2 * system.n_cut)
    return _value(system.dynamics(t, x, z, loops.mask)[1])


def test_projection_lands_on_the_rows_and_keeps_a_state_on_them(model):
    _, system, loops, x0, loop = model
    t = 0.2
    off = x0 + 1e-2 * RNG.standard_normal(len(x0))
    assert np.abs(_residuals(system, loops, t, off)).max() > 1e-4  # it is off them
    projected = _value(loop.project(t, off))
    # unit rows (per unit joint velocity): roundoff of the coordinates, ~1e-15 of 1
    np.testing.assert_allclose(_residuals(system, loops, t, projected), 0, rtol=0, atol=1e-13)
    # a second projection moves nothing beyond the first's roundoff
    np.testing.assert_allclose(_value(loop.project(t, projected)), projected, rtol=0,
                               atol=1e-13)
    # the correction is small where the drift is (the nearest point, not another branch)
    assert np.abs(projected - off).max() < 10 * np.abs(off - x0).max() + 1e-2


def test_velocity_correction_is_mass_orthogonal_to_the_rows_null_space(model):
    """At positions on the rows, the projected velocity differs from the given one by
    du = M^-1 P^T lam: M du is orthogonal to every motion the rows allow (null(P))."""
    _, system, loops, x0, loop = model
    n_theta = system.layout.n_theta
    x = x0.copy()
    x[n_theta:] += 0.5 * RNG.standard_normal(len(x) - n_theta)
    du = _value(loop.project(0.0, x))[n_theta:] - x[n_theta:]
    mass, jacobian, _, _ = (np.array(v.full()) for v in
                            saddle_terms(*_ir_tree(system, model))(0.0, x))
    kept = jacobian[loops.mask == 0]
    null = scipy.linalg.null_space(kept)
    assert null.shape[1] >= 1 and np.abs(du).max() > 1e-3
    # M du against the allowed motions, both O(1): roundoff
    np.testing.assert_allclose(null.T @ (mass @ du), 0, rtol=0, atol=1e-12)


def _ir_tree(system, model):
    return model[0].ir, system.tree


def test_positions_converge_within_the_fixed_iterations():
    """A drift of the loosest step's local error (1e-3 of coordinates ~1: rtol 1e-3) reaches
    roundoff in POSITION_ITERATIONS Gauss-Newton steps; one step fewer does not (the count is
    the least that does)."""
    functions, system, loops, x0, _ = _loops("four_bar_released")
    terms = saddle_terms(functions.ir, system.tree)
    off = x0 + 1e-3 * np.random.default_rng(1).standard_normal(len(x0))
    n = system.n_cut
    drift = []
    for iterations in (loop_ode.POSITION_ITERATIONS - 1, loop_ode.POSITION_ITERATIONS):
        loop = loop_ode.build(terms, system.dynamics, system.layout.n_theta, loops.mask,
                              iterations)
        drift.append(np.abs(_residuals(system, loops, 0.0, _value(loop.project(0.0, off)))
                            [:n]).max())
    assert drift[1] < 1e-14 < drift[0]
