"""The results rows' per-joint steps (formulations/tree_steps.py)."""

import casadi as ca
import numpy as np
import pytest

from casmech.core.euler import rotation
from casmech.formulations.tree_steps import tree_multipliers


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
