"""Estimation recovers the parameters that generated noisy synthetic measurements."""

from pathlib import Path

import numpy as np
import pytest

import casmech
from casmech.cli import main
from casmech.errors import UsageError
from casmech.optimal.estimate import estimate, read_measurements
from casmech.optimal.sensitivity import simulate
from casmech.output.csv import read_csv, write_csv

MODELS = Path(__file__).parents[2] / "models"
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
