"""The results rows' per-joint steps (formulations/tree_steps.py)."""

import casadi as ca
import numpy as np
import pytest

from casmech.core.euler import rotation
from casmech.formulations.tree_steps import translation_pivots, tree_multipliers


@pytest.mark.parametrize("rows", [3, 5, 6])
def test_tree_multipliers_recover_the_multipliers_of_a_wrench(rows):
    """A wrench made by known multipliers through -B^T lam comes back as those multipliers,
    and an arbitrary wrench as NumPy's least-squares solution of -B^T lam = f."""
    rng = np.random.default_rng(rows)
    block = rng.standard_normal((rows, 6))
    p = rng.standard_normal(4)
    turn = ca.DM(rotation(ca.DM(p / np.linalg.norm(p)))).full()
    lam = rng.standard_normal(rows)
    force = -block.T @ lam  # (global force, body-frame torque)
    wrench = np.concatenate([force[3:6], turn.T @ force[0:3]])  # (torque, force in body axes)
    (found,) = tree_multipliers(ca.DM(block), ca.DM(turn), ca.DM(wrench))
    # the Cholesky solve of the normal equations of a well-conditioned 3-6 row block
    np.testing.assert_allclose(ca.DM(found).full().ravel(), lam, rtol=1e-10, atol=1e-12)
    other = rng.standard_normal(6)
    (found,) = tree_multipliers(ca.DM(block), ca.DM(turn), ca.DM(other))
    given = np.concatenate([turn @ other[3:6], other[0:3]])
    expected = np.linalg.lstsq(-block.T, given, rcond=None)[0]
    # least squares of an inconsistent wrench: normal equations against NumPy's SVD solve
    np.testing.assert_allclose(ca.DM(found).full().ravel(), expected, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("others", [0, 2, 3])
def test_pivot_rows_give_the_multipliers_of_a_constraint_wrench(others):
    """Three rows holding a point (translation columns one +-1 each, anywhere among the
    rows) and `others` rotation rows: translation_pivots finds them, and the fast path
    recovers the multipliers of a wrench those rows exert, as the normal equations do."""
    rng = np.random.default_rng(10 + others)
    rows = 3 + others
    order, signs = rng.permutation(rows), rng.choice([-1.0, 1.0], 3)
    block = np.zeros((rows, 6))
    block[:, 3:6] = rng.standard_normal((rows, 3))
    for column in range(3):
        block[order[column], column] = signs[column]
    pivots = translation_pivots(ca.SX(ca.DM(block)))
    assert sorted(pivots) == sorted((order[c], c, signs[c]) for c in range(3))
    p = rng.standard_normal(4)
    turn = ca.DM(rotation(ca.DM(p / np.linalg.norm(p)))).full()
    lam = rng.standard_normal(rows)
    force = -block.T @ lam
    wrench = np.concatenate([force[3:6], turn.T @ force[0:3]])
    (fast,) = tree_multipliers(ca.DM(block), ca.DM(turn), ca.DM(wrench), pivots=pivots)
    (normal,) = tree_multipliers(ca.DM(block), ca.DM(turn), ca.DM(wrench))
    # both solve a consistent, well-conditioned system: the multipliers to roundoff
    np.testing.assert_allclose(ca.DM(fast).full().ravel(), lam, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(ca.DM(fast).full().ravel(), ca.DM(normal).full().ravel(),
                               rtol=1e-12, atol=1e-12)


def test_blocks_without_pivots():
    rng = np.random.default_rng(4)
    dense = rng.standard_normal((5, 6))
    assert translation_pivots(ca.SX(ca.DM(dense))) is None
    two = np.zeros((5, 6))  # a point held in two directions only (a prismatic joint's rows)
    two[0, 0], two[1, 1], two[:, 3:6] = 1.0, -1.0, rng.standard_normal((5, 3))
    assert translation_pivots(ca.SX(ca.DM(two))) is None
    scaled = np.zeros((3, 6))  # entries other than +-1
    scaled[0, 0], scaled[1, 1], scaled[2, 2] = 1.0, 2.0, 1.0
    assert translation_pivots(ca.SX(ca.DM(scaled))) is None
    symbolic = ca.SX(ca.DM(np.hstack([np.eye(3), np.zeros((3, 3))])))
    symbolic[1, 1] = ca.SX.sym("s")  # not a constant
    assert translation_pivots(symbolic) is None
