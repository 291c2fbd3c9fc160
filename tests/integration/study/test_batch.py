"""casmech.study.batch: many runs per call of the parametric library, against the closed-form
period of the gallery pendulum, against the same study made run by run, and its fallbacks."""

import numpy as np
import pytest

import casmech
from casmech.backends import codegen
from casmech.study import batch
from casmech.study.runner import Runner
from tests.conftest import MODELS
from tests.helpers.study import FOUR_BAR, G

pytestmark = pytest.mark.skipif(not codegen.available(), reason="no C compiler")
PENDULUM = MODELS / "pendulum.yaml"
FOUR_BAR_RELEASED = MODELS / "four_bar_released.yaml"
# what no_single_runs and a failing batch replace, put back by the tests that then compare
# (not by undoing the monkeypatch: that would undo the module's cache and -O0 too, and the
# runs alone would build the library again at the default flags)
RUN_ALONE, INTEGRATE = Runner.run, batch.Batch._integrate


@pytest.fixture(autouse=True)
def cache(tmp_path_factory, monkeypatch, quick_builds):
    """One compiled-model cache for this module's tests (the library is built once, at -O0)."""
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "batch-cache"))


@pytest.fixture
def no_single_runs(monkeypatch):
    """A run made one by one fails the test: the batch made them all."""
    def refuse(self, values):
        raise AssertionError(f"run {values} was made run by run")

    monkeypatch.setattr(Runner, "run", refuse)


def exact_period(L, theta0=1.0, r=0.05, rho=7800.0):
    """T = 4 sqrt(I_O / (m g L)) K(k), k = sin(theta0 / 2), of models/pendulum.yaml's ball on
    a massless rod (scipy's ellipk takes m = k^2)."""
    from scipy.special import ellipk

    m = rho * 4 / 3 * np.pi * r**3
    inertia = 2 / 5 * m * r**2 + m * L**2
    return 4 * np.sqrt(inertia / (m * G * L)) * ellipk(np.sin(theta0 / 2) ** 2)


def test_batched_periods_match_the_closed_form(no_single_runs, tmp_path):
    """The gallery pendulum over a length grid, at release amplitudes 1 rad and 2 rad: every
    period within 2e-6 s of the exact one."""
    for theta0 in (1.0, 2.0):
        table = casmech.sweep(PENDULUM, grid={"L": "0.5:2:40"}, mode="batched", workers=0,
                              overrides={"theta0": repr(theta0)}, out=tmp_path / str(theta0))
        assert set(table["status"]) == {"complete"} and len(table) == 40
        # the crossing interpolated between rows h = 5 ms apart errs by about
        # omega^2 h^3 / (36 sqrt 3) <= 4e-8 s per quarter period (kept.py); the integrator
        # (rtol 1e-9) by far less; 2e-6 s is the bound
        np.testing.assert_allclose(4 * table["crossing(bob.y)"],
                                   exact_period(table["L"].to_numpy(), theta0), rtol=0,
                                   atol=2e-6)
    import json

    metadata = json.loads((tmp_path / "1.0" / "metadata.json").read_text())
    assert metadata["study"]["runner"].startswith("batched")
    # the runs' casmech.compile mode at the top (the library's), batched in the options
    assert (metadata["mode"], metadata["options"]["mode"]) == ("compiled", "batched")


KEEP = ["max(bob.z)", "bob.vy@0.37", "min(pivot.fz)", "integral(energy)", "final(bob.wx)"]


def test_batched_runs_equal_the_study_made_run_by_run(no_single_runs, monkeypatch):
    """Positions, velocities, a reaction force (the joint's frame), the energy and the angular
    velocity of every run: the batch against each run made alone on the same library."""
    grid = {"L": [0.5, 0.77, 1.3, 2.0], "theta0": [0.3, 1.5]}
    batched = casmech.sweep(PENDULUM, grid=grid, keep=KEEP, mode="batched", workers=0)
    monkeypatch.setattr(Runner, "run", RUN_ALONE)  # runs one by one allowed again
    # method auto runs a batch by CVODES's Adams (study.batch) and a run alone by DOP853
    # (runtime.joint_dynamics.choose_method): the runs alone are asked for Adams
    alone = casmech.sweep(PENDULUM, grid=grid, keep=KEEP, mode="compiled", workers=0,
                          method="adams")
    assert list(batched["status"]) == ["complete"] * 8
    for column in KEEP:
        # the same integrator on the same compiled ODE from the same state; the model data
        # from the traced lowering instead of each run's own agrees to round-off, which the
        # integration (rtol 1e-9) could carry to ~1e-12 of the scale (they agree bit for bit
        # where the two data agree bit for bit, as here)
        scale = np.abs(alone[column]).max()
        np.testing.assert_allclose(batched[column], alone[column], rtol=0, atol=1e-12 * scale)


def test_initial_velocities_are_projected_as_a_run_projects_them(no_single_runs, monkeypatch,
                                                                 tmp_path):
    """The pendulum given an angular velocity and a radial velocity at release, which the
    joint does not allow: each run's velocities are the file's projected onto the
    constraints, as assembly does run by run."""
    model = tmp_path / "pendulum.yaml"
    model.write_text(PENDULUM.read_text().replace(
        "  theta0: 1.0 ", "  w0: 2.0\n  vr: 0.3\n  theta0: 1.0 ").replace(
        "    geometry:\n      - {sphere: r}",
        "    angular_velocity: [w0, 0, 0]\n"
        "    velocity: [0, vr * sin(theta0), -vr * cos(theta0)]\n"
        "    geometry:\n      - {sphere: r}"))
    grid = {"L": [0.5, 1.3], "w0": [-2.0, 3.0], "vr": [0.1, 0.3]}
    keep = ["max(bob.z)", "bob.vy@0.2", "final(bob.wx)"]
    batched = casmech.sweep(model, grid=grid, keep=keep, mode="batched", workers=0)
    monkeypatch.setattr(Runner, "run", RUN_ALONE)
    alone = casmech.sweep(model, grid=grid, keep=keep, mode="compiled", workers=0,
                          method="adams")  # the batch's method (as above)
    assert set(batched["status"]) == {"complete"}
    for column in keep:
        # the projection by the same least squares on Phi_q from the traced model instead of
        # the run's own (round-off apart), carried through the integration (rtol 1e-9)
        scale = np.abs(alone[column]).max()
        np.testing.assert_allclose(batched[column], alone[column], rtol=0, atol=1e-12 * scale)
    # the projection removes the radial velocity the rod does not allow: with 0.1 m/s and
    # 0.3 m/s of it, the same motion (to the least squares' round-off)
    pairs = batched.sort_values(["L", "w0", "vr"])["max(bob.z)"].to_numpy().reshape(-1, 2)
    np.testing.assert_allclose(pairs[:, 0], pairs[:, 1], rtol=0, atol=1e-12)


def test_a_failed_call_is_made_run_by_run(monkeypatch):
    """When the mapped call raises (a run whose integrator fails), every run of the chunk is
    made alone, so each failure carries its own reason."""
    def failing(self, x0, data, threads):
        raise RuntimeError("CVODES failed in one of the runs")

    monkeypatch.setattr(batch.Batch, "_integrate", failing)
    grid = {"L": [0.6, 1.4]}
    table = casmech.sweep(PENDULUM, grid=grid, mode="batched", workers=0)
    monkeypatch.setattr(batch.Batch, "_integrate", INTEGRATE)
    expected = casmech.sweep(PENDULUM, grid=grid, mode="compiled", workers=0)
    assert list(table["status"]) == ["complete", "complete"]
    assert list(table["crossing(bob.y)"]) == list(expected["crossing(bob.y)"])


def test_what_cannot_be_batched_says_why():
    """mode batched refuses a study it cannot make, with the reason and the way out."""
    with pytest.raises(casmech.UsageError, match=r"closed loops.*--mode compiled"):
        casmech.sweep(FOUR_BAR_RELEASED, grid={"m": [0.7, 0.8]}, mode="batched", workers=0,
                      t_end=0.1)
    with pytest.raises(casmech.UsageError, match=r"analysis type inverse_dynamics"):
        casmech.sweep(FOUR_BAR, grid={"a": [0.45, 0.5]}, mode="batched", workers=0,
                      t_end=0.1)
    # the model is invalid at a corner of the design (a negative density: a negative mass)
    with pytest.raises(casmech.UsageError, match=r"the model at \{'rho': -7800.0\}: .*E4"):
        casmech.sweep(PENDULUM, grid={"rho": [-7800.0, 7800.0]}, mode="batched", workers=0)


def test_auto_batches_a_large_study_only_where_it_can(monkeypatch):
    """auto: a study of COMPILE_RUNS runs or more of a tree's dynamics is batched; the same
    study of the pendulum with a damper (method auto examines each run's stiffness) is not."""
    from casmech.study import sweep as study

    prepared = study.prepare(PENDULUM, {"grid": {"L": "0.5:2:200"}})
    assert prepared.job.batched == ("L",)
    small = study.prepare(PENDULUM, {"grid": {"L": "0.5:2:20"}})
    assert small.job.batched == ()
    model = casmech.load(PENDULUM)
    settings = casmech.api.analysis_settings(casmech.compile(model))
    assert batch.obstacle(model, settings, prepared.study, full=True) == (
        "--full keeps every run's whole table")
    springy = casmech.loads(PENDULUM.read_text().replace("analysis:", (
        "forces:\n  - {name: damper, type: rsda, joint: pivot, damping: 0.1}\n\nanalysis:")),
        file=str(PENDULUM))
    assert batch.obstacle(springy, settings, prepared.study, full=False) == (
        "method auto examines each run's stiffness")
    explicit = casmech.loads(PENDULUM.read_text().replace("analysis:", (
        "analysis:\n  method: dop853")), file=str(PENDULUM))
    assert batch.obstacle(explicit, casmech.api.analysis_settings(casmech.compile(explicit)),
                          prepared.study, full=False) == (
        "method dop853 integrates each run by itself (a batch maps CVODES)")


def test_corners_of_the_design():
    points = [{"a": 1.0, "b": 5.0}, {"a": 3.0, "b": 5.0}, {"a": 2.0, "b": 4.0}]
    assert batch.corners(points, ["a", "b"]) == [{"a": 1.0, "b": 4.0}, {"a": 1.0, "b": 5.0},
                                                 {"a": 3.0, "b": 4.0}, {"a": 3.0, "b": 5.0}]


def test_the_command_line_batches_a_large_study(tmp_path):
    """`casmech sweep` of 200 lengths: auto batches it in this process, sweep.csv holds the
    exact periods."""
    import subprocess
    import sys

    import pandas as pd

    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "casmech.cli", "sweep", str(PENDULUM),
                           "--grid", "L=0.5:2:200", "--out", str(out)], capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert "200 runs on this process" in done.stderr and "batched" in done.stderr
    table = pd.read_csv(out / "sweep.csv")
    assert list(table["run"]) == list(range(200)) and set(table["status"]) == {"complete"}
    # as in test_batched_periods_match_the_closed_form
    np.testing.assert_allclose(4 * table["crossing(bob.y)"], exact_period(table["L"].to_numpy()),
                               rtol=0, atol=2e-6)


@pytest.mark.slow
def test_batched_tasks_on_a_cluster_give_the_same_rows():
    """Dask distributes batched tasks (each worker builds the batch once): the rows equal the
    study made in this process bit for bit, but the wall times."""
    pytest.importorskip("distributed")
    import pandas as pd

    grid = {"L": "0.5:2:24", "theta0": [0.5, 1.5]}
    here = casmech.sweep(PENDULUM, grid=grid, mode="batched", workers=0)
    cluster = casmech.sweep(PENDULUM, grid=grid, mode="batched", workers=2)
    pd.testing.assert_frame_equal(cluster.drop(columns="wall_s"), here.drop(columns="wall_s"),
                                  check_exact=True)
