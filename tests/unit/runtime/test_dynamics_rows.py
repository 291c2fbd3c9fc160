"""runtime.dynamics._Model.solved and runtime.joint_rows.LoopRows: a row whose saddle matrix
is singular (a joint written twice, no row masked) is solved by least squares, not left NaN,
and nothing is written to stderr (CasADi prints a failing mapped call's inputs)."""

from __future__ import annotations

import numpy as np
import pytest

import casmech
from casmech.core.options import DynamicsSolver
from casmech.formulations.builtin import velocities
from casmech.formulations.joint_system import saddle_terms
from casmech.formulations.table import BODY_FORMS
from casmech.runtime import dynamics, joint_dynamics
from casmech.runtime.assembly import initial_state
from casmech.runtime.joint_rows import LoopRows, solved_motion
from casmech.runtime.workspace import of

TWICE_HINGED = """casmech: 1
name: twice_hinged
bodies:
  - {name: bar, mass: 1.0, inertia: [0.01, 0.1, 0.1], position: [0.5, 0, 0]}
joints:
  - {name: hinge_a, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 0, 1]}
  - {name: hinge_b, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 0, 1]}
analysis: {type: dynamics, t_end: 0.1, output_step: 0.01}
"""


@pytest.mark.parametrize("name", ["rp", "romega"])
def test_a_singular_rows_accelerations_and_multipliers_solve_the_equations(name, capfd):
    functions = casmech.compile(casmech.loads(TWICE_HINGED))
    model, form = dynamics._Model(functions, name), BODY_FORMS[name]
    q, q_dot = initial_state(functions, 0.0, model.settings.assembly, model.workspace)
    v = velocities(functions, name, q, q_dot)
    s = model.scales(0.0, q)[0]
    state = np.concatenate([q, v, np.zeros(model.n_v)])[:, None]
    states, lam = model.solved(np.array([0.0]), state, np.zeros(model.m), s)
    v_dot, lam = states[model.n_q + model.n_v:, 0], lam[:, 0]
    assert np.all(np.isfinite(v_dot)) and np.all(np.isfinite(lam))
    mass, jacobian = functions.matrix(form.mass, q), functions.matrix(form.jacobian, 0.0, q)
    forces = functions.vector(form.forces, 0.0, q, v)
    gamma = functions.vector(form.gamma, 0.0, q, v)
    # the equations of motion the rows satisfy (a consistent singular system: exactly)
    np.testing.assert_allclose(mass @ v_dot + jacobian.T @ lam, forces, rtol=0,
                               atol=1e-12)  # roundoff of the least squares
    np.testing.assert_allclose(jacobian @ v_dot, gamma, rtol=0, atol=1e-12)  # as above
    # least norm: the two hinges (five rows each, in file order) share the load equally
    np.testing.assert_allclose(lam[:5], lam[5:10], rtol=0, atol=1e-12)  # as above
    assert np.abs(lam[:10]).max() > 1.0  # the bar's weight is carried (m g = 9.81 N)
    assert capfd.readouterr().err == ""


def test_a_singular_joint_loop_row_is_solved_by_least_squares_quietly(capfd):
    """The joint formulation cuts hinge_b, whose rows all depend on the tree's: its DAE masks
    them; with no row masked the row's saddle matrix is singular, and its least-squares row
    is the masked one (the cut rows carry nothing, the tree's hinge the weight)."""
    functions = casmech.compile(casmech.loads(TWICE_HINGED))
    system = joint_dynamics.joint_system(functions)
    workspace = of(functions, None)
    x, _, loops, signs = joint_dynamics._start(functions, system, 0.0,
                                               DynamicsSolver().assembly, workspace)
    assert loops.mask.sum() == 5  # hinge_b's five rows
    times, states = np.array([0.0, 0.01]), np.column_stack([x, x])
    terms = saddle_terms(functions.ir, system.tree)
    rows = solved_motion(terms, system.motion)

    def loop_rows(mask):
        return LoopRows(rows, lambda: terms, system.motion, mask)(times, states, signs)

    masked, singular = loop_rows(loops.mask), loop_rows(np.zeros(system.n_cut))
    for a, b in zip(masked, singular, strict=True):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-12)  # roundoff of the least squares
    assert np.abs(masked[3]).max() > 1.0  # the weight is carried (by hinge_a's rows)
    assert capfd.readouterr().err == ""


PROPPED = """casmech: 1
name: propped_bar
bodies:
  - {name: bar, mass: 1.0, inertia: [0.01, 0.1, 0.1], position: [0.5, 0, 0]}
joints:
  - {name: hinge, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 0, 1]}
  - {name: prop_a, type: spherical, body_i: ground, body_j: bar, at: [1, 0, 0]}
  - {name: prop_b, type: spherical, body_i: ground, body_j: bar, at: [1, 0, 0]}
gravity: [0, -9.81, 0]
analysis: {type: dynamics, t_end: 0.1, output_step: 0.01}
"""


def test_a_loop_column_singular_to_roundoff_is_solved_by_least_squares_quietly(capfd):
    """Two props at the tip of a hinged bar, both cut: their y rows (which the hinge's turn
    moves) are the same row twice. Unmasked, the fused rows' saddle solve is singular (not
    finite, numerics.kkt.solve_saddle), and LoopRows solves the column by least squares: the
    bar stays at rest and the props share their half of the weight equally (least norm)."""
    functions = casmech.compile(casmech.loads(PROPPED))
    system = joint_dynamics.joint_system(functions)
    x, _, loops, signs = joint_dynamics._start(functions, system, 0.0,
                                               DynamicsSolver().assembly, of(functions, None))
    terms = saddle_terms(functions.ir, system.tree)
    rows = solved_motion(terms, system.motion)
    unmasked = np.zeros(system.n_cut)
    fused = rows(0.0, x, unmasked, signs)
    assert not np.all(np.isfinite(np.array(fused[3])))  # the fallback is what is tested
    times, states = np.array([0.0, 0.01]), np.column_stack([x, x])
    _, _, q_ddot, lam = LoopRows(rows, lambda: terms, system.motion, unmasked)(times, states,
                                                                             signs)
    np.testing.assert_allclose(q_ddot, 0.0, rtol=0, atol=1e-12)  # at rest: roundoff
    prop_a, prop_b = (list(functions.ir.joints[k].rows) for k in (1, 2))
    weight = 9.81 * 0.5  # the props carry the bar's weight at its tip: m g (0.5 / 1)
    np.testing.assert_allclose(lam[prop_a[1]], lam[prop_b[1]], rtol=0,
                               atol=1e-12)  # least norm: equal shares, to roundoff
    np.testing.assert_allclose(np.abs(lam[prop_a[1]] + lam[prop_b[1]]), weight, rtol=1e-12,
                               atol=0)  # their sum is the static tip load, to roundoff
    assert capfd.readouterr().err == ""
