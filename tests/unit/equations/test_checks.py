"""equations.checks: rank and redundant rows by a sparse QR agree with dense Gram-Schmidt (the
former implementation, kept here as the reference) on the gallery, Bricard's redundant row,
the IFToMM A02 four-bar at its flat (singular) pose, and random sparse matrices."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.core.options import LinearAlgebra
from casmech.equations import checks
from casmech.numerics import numeric_qr
from casmech.runtime import assembly
from tests.conftest import MODELS
from tests.helpers.a02_model import a02_model

LIMITS = LinearAlgebra()  # the defaults (casmech.core.options)


def dense_independent_rows(matrix, tolerance=LIMITS.rank_tolerance):
    """Greedy in row order by two-pass Gram-Schmidt over dense rows (the former checks code)."""
    scale = max(np.linalg.norm(matrix, 2), 1.0) if matrix.size else 1.0
    basis, keep = [], []
    for row in matrix:
        residual = row.copy()
        for _ in range(2):
            for b in basis:
                residual -= (b @ residual) * b
        norm = np.linalg.norm(residual)
        keep.append(bool(norm > tolerance * scale))
        if keep[-1]:
            basis.append(residual / norm)
    return keep


def structure_order(functions):
    n_joint_rows = functions.n_rows - functions.n_bodies
    return list(range(n_joint_rows, functions.n_rows)) + list(range(n_joint_rows))


def assert_same_as_dense(functions, q):
    report = checks.structure(functions, 0.0, q)
    phi_q = functions.matrix("phi_q", 0.0, q)
    order = structure_order(functions)
    keep = dict(zip(order, dense_independent_rows(phi_q[order]), strict=True))
    assert report.independent == tuple(k for k in range(functions.n_rows) if keep[k])
    assert report.rank == np.linalg.matrix_rank(phi_q, tol=LIMITS.rank_tolerance
                                                * max(np.linalg.norm(phi_q, 2), 1.0))
    return report


@pytest.mark.parametrize("path", sorted(MODELS.glob("*.yaml")) + [
    MODELS / "validation" / "iftomm_a02_four_bar_N2.yaml"], ids=lambda path: path.stem)
def test_gallery_structure_equals_dense(path):
    functions = casmech.compile(casmech.load(path))
    for q in (assembly.initial_guess(functions), assembly.assemble_positions(functions)):
        assert_same_as_dense(functions, q)


def test_bricard_redundant_row_is_the_last_hinge():
    """IFToMM A04: the 6R loop has one dependent row; scanned in file order it is blamed on a
    row of the last hinge, the same row the dense scan finds."""
    functions = casmech.compile(casmech.load(MODELS / "bricard.yaml"))
    report = assert_same_as_dense(functions, assembly.assemble_positions(functions))
    assert report.dof == 1 and len(report.redundant) == 1
    assert report.redundant[0].joint == "hinge5"


def a02_flat_pose(functions, n):
    """Every crank turned by pi/2 about z (lying along -x from its pivot), couplers on the x
    axis: the flat pose where the N-four-bar's constraint Jacobian loses rank."""
    half = 1.0 / 2  # L = 1 in the validation model
    r = [[i - half, 0.0, 0.0] for i in range(n + 1)] + [[i - half, 0.0, 0.0] for i in range(n)]
    p = [[np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)]] * (n + 1) + [[1.0, 0, 0, 0]] * n
    q = np.concatenate([np.ravel(r), np.ravel(p)])
    assert np.max(np.abs(functions.vector("phi", 0.0, q))) < 1e-12  # an assembled pose
    return q


@pytest.mark.parametrize("n", [1, 2, 5])
def test_a02_flat_pose_equals_dense(n):
    functions = casmech.compile(casmech.loads(a02_model(n)))
    upright = assert_same_as_dense(functions, assembly.assemble_positions(functions))
    flat = assert_same_as_dense(functions, a02_flat_pose(functions, n))
    assert upright.dof == 1 and flat.dof > upright.dof and flat.redundant


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("dense_qr", [0, LIMITS.dense_qr_entries], ids=["sparse", "dense"])
def test_random_sparse_rows_with_planted_dependencies(seed, dense_qr):
    """Rows that are combinations of earlier rows (or zero, or a copy) are found, in a sparse
    matrix as wide as the r-p Jacobians (more coordinates than rows) and a square one, by
    numeric_qr's own factorization and by LAPACK's (its dense path)."""
    limits = LinearAlgebra(dense_qr_entries=dense_qr)
    rng = np.random.default_rng(seed)
    rows, columns = (30, 45) if seed % 2 else (40, 40)
    matrix = rng.standard_normal((rows, columns)) * (rng.random((rows, columns)) < 0.15)
    for k in rng.choice(np.arange(5, rows), size=6, replace=False):
        earlier = rng.choice(k, size=2, replace=False)
        matrix[k] = rng.standard_normal(2) @ matrix[earlier]
    matrix[4] = 0.0
    keep = checks.independent_rows(ca.DM(matrix), limits)
    assert keep == dense_independent_rows(matrix)
    assert sum(keep) == np.linalg.matrix_rank(matrix)


def test_more_rows_than_columns():
    rng = np.random.default_rng(3)
    matrix = rng.standard_normal((9, 4))
    assert checks.independent_rows(ca.DM(matrix)) == [True] * 4 + [False] * 5


@pytest.mark.parametrize("shape", [(20, 30), (200, 300)])  # dense SVD; power iteration
def test_norm2_equals_the_dense_spectral_norm(shape):
    rng = np.random.default_rng(5)
    matrix = rng.standard_normal(shape) * (rng.random(shape) < 0.02)
    matrix[:5, :5] += 10.0  # a well separated largest singular value (~50 against ~2)
    assert (matrix.size > LIMITS.dense_norm_entries) == (shape == (200, 300))
    # power iteration stops at 1e-10 relative change; the SVD is exact to roundoff
    np.testing.assert_allclose(numeric_qr.norm2(ca.DM(matrix)), np.linalg.norm(matrix, 2),
                               rtol=1e-8, atol=0)


SLIDER_AT_ORIGIN = """
casmech: 1
name: slider
bodies:
  - {name: block, mass: 1.0, inertia: [0.1, 0.1, 0.1], position: [0, 0, 0]}
joints:
  - {name: rail, type: translational, body_i: ground, body_j: block, at: [0, 0, 0], axis: [1, 0, 0]}
  - {name: tether, type: d, body_i: ground, s_i: [0, 0, 0], body_j: block, s_j: [0, 0, 0]}
"""


def test_dependent_joints_sparse_equals_dense_on_a_single_dependency():
    """A block on a rail, tethered at zero distance: the tether's row of Phi_q vanishes (the
    only dependency), so both paths give it all the weight (the sparse one forced by a zero
    dense_svd_entries)."""
    functions = casmech.compile(casmech.loads(SLIDER_AT_ORIGIN))
    phi_q = functions["phi_q"](0.0, assembly.initial_guess(functions))
    dense = checks.dependent_joints(functions, np.array(phi_q))
    sparse = checks.dependent_joints(functions, phi_q,
                                     limits=LinearAlgebra(dense_svd_entries=0))
    assert dense[0][0] == sparse[0][0] == "tether"
    # a unit weight and zeros, up to the SVD's roundoff
    np.testing.assert_allclose([w for _, _, w in sparse], [w for _, _, w in dense], rtol=0,
                               atol=1e-12)
