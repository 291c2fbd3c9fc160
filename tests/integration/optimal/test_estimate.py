"""Estimation recovers the parameters that generated noisy synthetic measurements."""


import numpy as np
import pytest

import casmech
from casmech.cli import main
from casmech.errors import UsageError
from casmech.io.csv import read_csv, read_measurements, write_csv
from casmech.optimal.estimate import estimate
from casmech.optimal.sensitivity import simulate
from tests.conftest import MODELS

PENDULUM = MODELS / "estimate_pendulum.yaml"
TRUTH = {"m": "2", "c": "0.15"}  # the file holds the starting values m = 1.5, c = 0.3
TIMES = np.arange(1, 81) * 0.025


def measurements() -> np.ndarray:
    """bar.y, bar.z of the true pendulum plus 0.5 mm Gaussian noise (fixed seed)."""
    clean = simulate(casmech.load(PENDULUM, TRUTH), ["bar.y", "bar.z"], TIMES)
    return clean + np.random.default_rng(7).normal(0.0, 5e-4, clean.shape)


def test_pendulum_mass_and_damping_from_noisy_positions(tmp_path, capsys):
    """Measurements generated here (true m, c plus noise, fixed seed) are the committed example
    data, and `casmech optimize` fits m and c to them from the file's starting values."""
    names, committed = read_csv(MODELS / "estimate_pendulum_measured.csv")
    assert names == ["t", "bar.y", "bar.z"]
    np.testing.assert_allclose(committed[:, 0], TIMES, rtol=0, atol=1e-15)  # written with %.17g
    # the regenerated data differ from the committed ones by the integration's roundoff, which
    # depends on the machine (measured 0 where they were written, 2.1e-9 m on another VM):
    # 1e-8 m is 1/50000 of the noise they carry
    np.testing.assert_allclose(committed[:, 1:], measurements(), rtol=0, atol=1e-8)
    assert main(["optimize", str(PENDULUM), "--out", str(tmp_path)]) == 0
    _, table = read_csv(tmp_path / "estimate.csv")
    np.testing.assert_allclose(table[:, 0], [1.5, 0.3], rtol=0, atol=0)  # the file's values
    # the bound: within 1% of the generating values (measured 0.03% for m, 0.12% for c)
    np.testing.assert_allclose(table[:, 1], [2.0, 0.15], rtol=1e-2, atol=0)
    out = capsys.readouterr().out
    assert "m  1.5 -> " in out
    # at the optimum the residuals are the noise: their RMS is the noise level (160 samples of
    # sigma 5e-4 give 5e-4 +- 6%; measured 4.45e-4 with this seed)
    rms = float(out.split("residual RMS ")[1].split()[0])
    assert 4e-4 < rms < 6e-4


def test_estimate_api_with_weights_ignores_an_unweighted_column():
    """A column with weight 0 does not move the fit: corrupting it changes nothing."""
    model = casmech.load(PENDULUM, TRUTH)
    times = TIMES[::8]
    clean = simulate(model, ["bar.y", "bar.z"], times)
    data = {"bar.y": clean[:, 0], "bar.z": clean[:, 1] + 0.3}
    start = casmech.load(PENDULUM, {"m": "2"})  # the true mass; c starts at 0.3
    fit = estimate(start, ["c"], times, data, weights={"bar.z": 0.0})
    # noise-free data on bar.y alone pin c (measured 1e-8 relative)
    np.testing.assert_allclose(fit.values, [0.15], rtol=1e-5, atol=0)


def test_measurements_need_a_time_column(tmp_path):
    path = write_csv(tmp_path / "bad.csv", ["time", "bar.y"], np.zeros((3, 2)))
    with pytest.raises(UsageError, match="'t' column"):
        read_measurements(path)


def runtime_columns(model, columns, times, analysis="dynamics") -> np.ndarray:
    """Columns of casmech's own run (the runtime, not casmech.optimal's IDAS graph) at `times`,
    interpolated from a 1 ms output grid by cubic splines."""
    from scipy.interpolate import CubicSpline
    result = casmech.analyze(casmech.compile(model), analysis, t_end=float(times[-1]),
                             output_step=1e-3, rtol=1e-11, atol=1e-13)
    frame = result.to_dataframe()
    return np.column_stack([CubicSpline(frame.index, frame[c])(times) for c in columns])


def test_pendulum_length_and_initial_angle_from_positions():
    """Geometry: the bar's length L (its joint point, centre and inertia-free positions) and
    initial angle a0 (its orientation) fitted to positions of casmech's runtime at L = 1.2,
    a0 = 0.8, from the file's L = 1, a0 = 1."""
    times = TIMES[::4]
    truth = casmech.load(PENDULUM, {"L": "1.2", "a0": "0.8"})
    clean = runtime_columns(truth, ["bar.y", "bar.z"], times)
    fit = estimate(casmech.load(PENDULUM), ["L", "a0"], times,
                   {"bar.y": clean[:, 0], "bar.z": clean[:, 1]}, bounds={"L": (0.5, 2.0)})
    assert fit.status == "Solve_Succeeded"
    np.testing.assert_allclose(fit.initial, [1.0, 1.0], rtol=0, atol=0)  # the file's values
    # noise-free data: the fit is limited by the spline of the 1 ms grid (~1e-9 m) and the
    # integrators' tolerances (1e-9 relative), both far below 1e-6 of the parameters
    np.testing.assert_allclose(fit.values, [1.2, 0.8], rtol=1e-6, atol=0)


def test_composed_chain_link_length():
    """A composed model (repeat): the link length of a 2-link chain fitted to the tip's
    positions of casmech's runtime at L = 0.6, from the file's L = 0.5."""
    times = np.arange(1, 11) * 0.05
    columns = ["link2.bar.x", "link2.bar.z"]
    truth = casmech.load(MODELS / "chain_repeat.yaml", {"N": "2", "L": "0.6"})
    clean = runtime_columns(truth, columns, times)
    start = casmech.load(MODELS / "chain_repeat.yaml", {"N": "2"})
    fit = estimate(start, ["L"], times, dict(zip(columns, clean.T, strict=True)))
    assert fit.status == "Solve_Succeeded"
    # noise-free data, as above
    np.testing.assert_allclose(fit.values, [0.6], rtol=1e-6, atol=0)


# the estimate_pendulum bar hung from a pivot at (0, py, pz)
PIVOTED = PENDULUM.read_text().replace("  Ic: 0.02", "  Ic: 0.02\n  py: 0.0\n  pz: 0.0").replace(
    "position: [0, L/2 * sin(a0), -L/2 * cos(a0)]",
    "position: [0, py + L/2 * sin(a0), pz - L/2 * cos(a0)]").replace(
    "at: [0, 0, 0]", "at: [0, py, pz]")


def test_pendulum_length_and_pivot_from_positions():
    """The bar's length and its pivot's position (a joint point and the bar's initial
    position, both geometry) fitted to positions of casmech's runtime at L = 1.2,
    pivot (0, 0.1, -0.2), from the file's L = 1 and pivot at the origin."""
    times = TIMES[::4]
    truth = casmech.loads(PIVOTED, overrides={"L": "1.2", "py": "0.1", "pz": "-0.2"})
    clean = runtime_columns(truth, ["bar.y", "bar.z"], times)
    fit = estimate(casmech.loads(PIVOTED), ["L", "py", "pz"], times,
                   {"bar.y": clean[:, 0], "bar.z": clean[:, 1]}, bounds={"L": (0.5, 2.0)})
    assert fit.status == "Solve_Succeeded"
    np.testing.assert_allclose(fit.initial, [1.0, 0.0, 0.0], rtol=0, atol=0)  # the file's
    # noise-free data: as for L and a0 above (the spline of the 1 ms grid, ~1e-9 m)
    np.testing.assert_allclose(fit.values, [1.2, 0.1, -0.2], rtol=1e-6, atol=1e-7)


def test_four_bar_link_lengths_from_positions():
    """models/four_bar.yaml (driven crank, 0 DOF): the coupler and rocker lengths b and c,
    which set the whole initial pose through the file's loop-closure expressions, fitted to
    the coupler's and rocker's positions of casmech's kinematics at b = 2.1, c = 1.45, from
    the file's b = 2, c = 1.5."""
    path = MODELS / "four_bar.yaml"
    times = np.arange(1, 21) * 0.05
    columns = ["coupler.x", "coupler.y", "rocker.x", "rocker.y"]
    clean = runtime_columns(casmech.load(path, {"b": "2.1", "c": "1.45"}), columns, times,
                            "kinematics")
    fit = estimate(casmech.load(path), ["b", "c"], times,
                   dict(zip(columns, clean.T, strict=True)))
    assert fit.status == "Solve_Succeeded"
    # noise-free data, as above
    np.testing.assert_allclose(fit.values, [2.1, 1.45], rtol=1e-6, atol=0)
