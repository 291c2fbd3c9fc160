"""runtime.joint_rows.solved_motion, the joint loop rows with their multipliers solved at each
state as one SX Function, against the same rows composed of three Functions (the saddle terms,
numerics.kkt.saddle's CSparse LU, the results rows) and against the r-p formulation's
multipliers, solved at the same r-p state (a second formulation), at random states of a
spatial four-bar and of a gear pair (a coupling cut as a closure row)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.formulations.builtin import velocities
from casmech.formulations.joint_system import saddle_terms
from casmech.formulations.table import BODY_FORMS
from casmech.numerics import kkt
from casmech.runtime.joint_dynamics import joint_system
from casmech.runtime.joint_rows import solved_motion
from tests.conftest import MODELS

RNG = np.random.default_rng(5)
LOOP_MODELS = ("four_bar", "gear_pair")


def composed(terms: ca.Function, motion: ca.Function):
    """(t, x, w, signs) -> (q, q_dot, q_ddot, lam) by the three Functions one after another."""
    saddle = kkt.saddle(terms.sparsity_out(0), terms.sparsity_out(1))

    def rows(t, x, w, signs):
        mass, jacobian, forces, gamma = terms(t, x)
        _, lam = saddle(mass, jacobian, forces, gamma, w)
        return motion(t, x, ca.vertcat(lam, ca.DM.zeros(lam.numel())), signs)[:4]

    return rows


def rp_multipliers(functions, t: float, q: np.ndarray, q_dot: np.ndarray) -> np.ndarray:
    """The joint rows' multipliers of the r-p equations of motion at (t, q, q_dot): the
    saddle system [M Phi_q^T; Phi_q 0] [v_dot; lam] = [F; gamma] solved by LAPACK."""
    form = BODY_FORMS["rp"]
    v = velocities(functions, "rp", q, q_dot)
    mass, jacobian = functions.matrix(form.mass, q), functions.matrix(form.jacobian, t, q)
    forces, gamma = functions.vector(form.forces, t, q, v), functions.vector(form.gamma, t, q, v)
    m = jacobian.shape[0]
    lhs = np.block([[mass, jacobian.T], [jacobian, np.zeros((m, m))]])
    solution = np.linalg.solve(lhs, np.concatenate([forces, gamma]))
    return solution[len(forces):][:functions.n_joint_rows]


def assert_rows_agree(functions, system, rows: ca.Function, terms: ca.Function,
                      states: int = 4) -> None:
    """rows (solved_motion's, compiled or not) equals the three-function composition and
    its multipliers the r-p formulation's, at random (t, x)."""
    reference = composed(terms, system.motion)
    nb, m = functions.n_bodies, system.n_cut
    for _ in range(states):
        t, x = RNG.uniform(0, 1), RNG.uniform(-0.5, 0.5, system.layout.n_x)
        fused = [np.array(v).ravel() for v in rows(t, x, np.zeros(m), np.ones(nb))]
        three = [np.array(v).ravel() for v in reference(t, x, np.zeros(m), np.ones(nb))]
        for a, b in zip(fused, three, strict=True):
            # one set of equations, a QR against an LU solve of the same small system:
            # roundoff times its condition, relative to the largest entry
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-10 * max(1.0, np.abs(b).max()))
        q, q_dot, _, lam = fused
        rp = rp_multipliers(functions, t, q, q_dot)
        # the r-p equations at the same state (its velocity constraints the tree's): the
        # same multipliers, to roundoff times the two systems' conditions
        np.testing.assert_allclose(lam[:len(rp)], rp, rtol=0, atol=1e-9 * np.abs(rp).max())
        assert np.abs(rp).max() > 1e-3  # the loads are carried (the check is not of zeros)


@pytest.mark.parametrize("name", LOOP_MODELS)
def test_the_fused_loop_rows_are_the_composed_ones_and_the_rp_multipliers(name):
    functions = casmech.compile(casmech.load(MODELS / f"{name}.yaml"))
    system = joint_system(functions)
    assert system.n_cut
    terms = saddle_terms(functions.ir, system.tree)
    rows = solved_motion(terms, system.motion)
    assert rows.is_a("SXFunction")  # one graph: terms, solve and rows inlined
    assert_rows_agree(functions, system, rows, terms)
