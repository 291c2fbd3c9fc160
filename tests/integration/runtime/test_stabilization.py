"""How dynamics keeps the constraints: the stabilized index-2 DAE (ggl, the default) against the
index-1 DAE with projections (formulations.dae, runtime.dynamics)."""

import subprocess
import sys

import numpy as np
import pytest

import casmech
from casmech.core.options import DynamicsSolver
from casmech.errors import UsageError
from casmech.formulations.dae_options import initial_step
from tests.conftest import MODELS, Table
from tests.helpers.reference_data import VALIDATION_MODELS as VALIDATION

DRIFT_TOLERANCE = DynamicsSolver().drift_tolerance  # the default (casmech.core.options)

# Three 1 m, 1 kg bars in a spherical chain, released level (the benchmarks' chain, N = 3).
CHAIN = """
casmech: 1
name: chain3
gravity: [0, -9.81, 0]
bodies:
  - {name: b1, mass: 1, inertia: [1.0e-4, 0.0833333333, 0.0833333333], position: [0.5, 0, 0]}
  - {name: b2, mass: 1, inertia: [1.0e-4, 0.0833333333, 0.0833333333], position: [1.5, 0, 0]}
  - {name: b3, mass: 1, inertia: [1.0e-4, 0.0833333333, 0.0833333333], position: [2.5, 0, 0],
     velocity: [0, 0, 0.3]}
joints:
  - {name: s1, type: spherical, body_i: ground, body_j: b1, at: [0, 0, 0]}
  - {name: s2, type: spherical, body_i: b1, body_j: b2, at: [1, 0, 0]}
  - {name: s3, type: spherical, body_i: b2, body_j: b3, at: [2, 0, 0]}
analysis: {type: dynamics, t_end: 4, output_step: 0.01, rtol: 1.0e-10, atol: 1.0e-12}
"""


def run(text_or_path, **kwargs):
    model = (casmech.load(text_or_path) if not isinstance(text_or_path, str)
             else casmech.loads(text_or_path))
    functions = casmech.compile(model)
    result = casmech.analyze(functions, "dynamics", **kwargs)
    return functions, result, Table(*casmech.results_table(functions, result))


@pytest.fixture(scope="module")
def chain_runs():
    return {kind: run(CHAIN, stabilization=kind) for kind in ("ggl", "projection")}


def test_ggl_keeps_the_constraints_without_projections(chain_runs):
    """The index-2 DAE holds Phi = 0 and P v = nu at every step, so a 4 s run of the whipping
    chain needs no projection, where the index-1 DAE drifts past 1e-9 and is projected."""
    functions, result, table = chain_runs["ggl"]
    _, projected, projected_table = chain_runs["projection"]
    print(f"\nchain3: max |Phi| {table['constraint_violation'].max():.1e} (ggl, "
          f"{result.metadata['projections']} projections), "
          f"{projected_table['constraint_violation'].max():.1e} (index-1, "
          f"{projected.metadata['projections']} projections)")
    assert result.metadata["stabilization"] == "ggl" and result.metadata["ggl_failed_at"] is None
    assert result.metadata["projections"] == 0 < projected.metadata["projections"]
    assert table["constraint_violation"].max() <= DRIFT_TOLERANCE
    # conservative: energy constant to 1e-8 of the largest kinetic energy (issue 3's bound)
    kinetic = [functions.evaluate("energy", t, q, q_dot)[0].item()
               for t, q, q_dot in zip(result.times, result.q, result.q_dot, strict=True)]
    assert np.ptp(table["energy"]) <= 1e-8 * max(kinetic)


def test_ggl_and_projection_give_the_same_motion(chain_runs):
    """Two different DAEs and drift treatments: positions, velocities and reactions agree to the
    integration error (each ~1e-8 at rtol 1e-10 over 4 s of the chain, measured 2e-8)."""
    _, _, ggl = chain_runs["ggl"]
    _, _, projected = chain_runs["projection"]
    for column in ("b3.x", "b3.y", "b3.z", "b3.vx", "b2.wz", "b3.e1"):
        np.testing.assert_allclose(ggl[column], projected[column], rtol=0, atol=1e-6,
                                   err_msg=column)
    for column in ("s1.fx", "s1.fy", "s3.fz"):  # reactions: 1e-6 of their ~30 N scale
        np.testing.assert_allclose(ggl[column], projected[column], rtol=0, atol=3e-5,
                                   err_msg=column)


@pytest.mark.parametrize("formulation", ["rp", "romega"])
def test_ggl_handles_redundant_rows(formulation):
    """Bricard (a closed loop with one redundant row, masked out of both DAEs): ggl and the
    index-1 DAE with projections give the same motion and minimum-norm reactions (1e-7, the
    r-p/r-omega bound of issue 3, at rtol 1e-12)."""
    tables = {kind: run(MODELS / "bricard.yaml", t_end=1, rtol=1e-12, atol=1e-14,
                        formulation=formulation, stabilization=kind)
              for kind in ("ggl", "projection")}
    assert tables["ggl"][1].metadata["stabilization"] == "ggl"
    assert tables["ggl"][1].metadata["dropped_rows"] == 1
    for column in ("rod1.x", "rod3.z", "rod4.wy", "hinge2.fx", "hinge4.ty"):
        a, b = tables["ggl"][2][column], tables["projection"][2][column]
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-7 * max(1.0, np.max(np.abs(b))),
                                   err_msg=column)


def test_ggl_falls_back_at_singular_poses():
    """IFToMM A02 reaches a flat (singular) pose at 0.72 s: the index-2 DAE fails there, then the
    index-1 one, and the run is done again from t0 on the augmented-Lagrangian ODE, each step
    recorded; its accuracy against the exact solution is test_validation_iftomm's."""
    _, result, table = run(VALIDATION / "iftomm_a02_four_bar_N2.yaml", t_end=1)
    assert result.metadata["ggl_failed_at"] is not None
    assert result.metadata["dae_failed_at"] is not None
    assert result.metadata["augmented_from"] == 0.0
    assert table["t"][-1] == pytest.approx(1.0)


def test_initial_step_closed_form():
    """One translation with r_ddot = a: h0 with h0^2 / 2 a = w / 4 (a quarter of the weighted
    tolerance, so h0 = 0.5 sqrt(2 w / a)); capped at 0.001 of the first interval; that cap when
    nothing accelerates."""
    w = 1e-8 * 2.0 + 1e-10
    h = initial_step(np.array([2.0]), np.array([9.81]), 1e-8, 1e-10, 1.0)
    np.testing.assert_allclose(h, 0.5 * np.sqrt(2 * w / 9.81), rtol=1e-14, atol=0)
    assert initial_step(np.array([2.0]), np.array([1e-12]), 1e-8, 1e-10, 0.01) == 1e-5
    assert initial_step(np.array([2.0]), np.array([0.0]), 1e-8, 1e-10, 0.01) == 1e-5


def test_stabilization_is_chosen_by_model_api_and_cli(tmp_path):
    text = CHAIN.replace("atol: 1.0e-12}", "atol: 1.0e-12, stabilization: projection}")
    functions = casmech.compile(casmech.loads(text))
    assert casmech.analyze(functions, t_end=0.05).metadata["stabilization"] == "projection"
    assert casmech.analyze(functions, t_end=0.05,
                           stabilization="ggl").metadata["stabilization"] == "ggl"
    with pytest.raises(UsageError, match="stabilization 'index2' is not one of ggl, projection"):
        casmech.analyze(functions, t_end=0.05, stabilization="index2")
    path = tmp_path / "chain.yaml"
    path.write_text(CHAIN.replace("atol: 1.0e-12}", "atol: 1.0e-12, stabilization: baumgarte}"))
    out = subprocess.run([sys.executable, "-m", "casmech.cli", "check", str(path)],
                         capture_output=True, text=True)
    assert out.returncode != 0
    line = next(k for k, s in enumerate(path.read_text().splitlines(), 1) if "baumgarte" in s)
    assert f"chain.yaml:{line}:" in out.stderr and "stabilization" in out.stderr, out.stderr
    path.write_text(CHAIN)
    out = subprocess.run([sys.executable, "-m", "casmech.cli", "run", str(path), "--t-end", "0.05",
                          "--stabilization", "projection", "--out", str(tmp_path / "out")],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert '"stabilization": "projection"' in (tmp_path / "out" / "metadata.json").read_text()
