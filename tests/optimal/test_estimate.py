"""Estimation recovers the parameters that generated noisy synthetic measurements."""

from pathlib import Path

import numpy as np
import pytest

import casmech
from casmech.errors import UsageError
from casmech.optimal.estimate import estimate, read_measurements
from casmech.optimal.sensitivity import simulate
from casmech.output.csv import write_csv

PENDULUM = Path(__file__).parents[2] / "models" / "estimate_pendulum.yaml"


def test_pendulum_mass_and_damping_from_noisy_positions(tmp_path):
    truth = casmech.load(PENDULUM)  # m = 2, c = 0.15
    times = np.arange(1, 81) * 0.025
    clean = simulate(truth, ["bar.y", "bar.z"], times)
    noisy = clean + np.random.default_rng(7).normal(0.0, 5e-4, clean.shape)  # 0.5 mm tracker
    path = write_csv(tmp_path / "measured.csv", ["t", "bar.y", "bar.z"],
                     np.column_stack([times, noisy]))
    measured_times, data = read_measurements(path)
    start = casmech.load(PENDULUM, {"m": "1.5", "c": "0.3"})
    fit = estimate(start, ["m", "c"], measured_times, data, bounds={"m": (0.1, 10), "c": (0, 5)})
    # the bound: within 1% of the generating values (measured 0.4% for m, 0.2% for c)
    np.testing.assert_allclose(fit.values, [2.0, 0.15], rtol=1e-2, atol=0)
    # at the optimum the residuals are the noise: their RMS is the noise level (80 x 2 samples)
    assert 4e-4 < np.sqrt(np.mean(fit.residuals ** 2)) < 6e-4


def test_measurements_need_a_time_column(tmp_path):
    path = write_csv(tmp_path / "bad.csv", ["time", "bar.y"], np.zeros((3, 2)))
    with pytest.raises(UsageError, match="'t' column"):
        read_measurements(path)
