"""Mode shapes played by `casmech animate --mode` (io/mode_animation.py), against the
compound pendulum's closed form."""

import numpy as np
import pytest

from casmech.cli import main
from casmech.errors import UsageError
from casmech.io.mode_animation import mode_table, read_linear_model
from tests.helpers.statics_models import HANGING_ROD, G

M, LENGTH, W = 1.5, 0.8, 0.03  # HANGING_ROD's parameters
ARM = LENGTH / 2


def rod_frames(tmp_path, amplitude: float, cycles: float = 2.0):
    model_file = tmp_path / "rod.yaml"
    model_file.write_text(HANGING_ROD)
    assert main(["run", str(model_file), "--out", str(tmp_path / "run")]) == 0
    linear = read_linear_model(tmp_path / "run" / "linear_model.npz")
    return mode_table(linear, ("rod",), 1, amplitude, cycles)


def test_rod_mode_turns_about_the_pivot_by_the_amplitude_at_its_frequency(tmp_path):
    amplitude = 0.02
    names, values = rod_frames(tmp_path, amplitude)
    column = {name: k for k, name in enumerate(names)}
    omega = np.sqrt(M * G * ARM / (M * (LENGTH**2 + W**2) / 12 + M * ARM**2))
    # two periods of the closed-form frequency (rtol 1e-10: the modal eigenvalue's accuracy)
    np.testing.assert_allclose(values[-1, column["t"]], 2 * 2 * np.pi / omega, rtol=1e-10, atol=0)
    e = values[:, [column[f"rod.e{k}"] for k in range(4)]]
    np.testing.assert_allclose(np.linalg.norm(e, axis=1), 1.0, rtol=0, atol=1e-14)
    # the rod hangs (angle 0 about y at equilibrium): its angle about y swings +-amplitude, the
    # first-order shape normalized (2 atan(a / 2) = a - a^3 / 12: rtol a^2)
    angle = 2 * np.arctan2(e[:, 2], e[:, 0])
    np.testing.assert_allclose(np.max(np.abs(angle)), amplitude, rtol=amplitude**2, atol=0)
    np.testing.assert_allclose(np.abs(e[:, [1, 3]]), 0.0, rtol=0, atol=1e-14)  # about y only
    # rigid rotation about the pivot to first order: the pivot point (ARM along the rod's
    # body z from its CM) stays at the origin within ARM * amplitude^2
    r = values[:, [column[f"rod.{c}"] for c in "xyz"]]
    pivot = r + ARM * np.column_stack([np.sin(angle), np.zeros(len(angle)), np.cos(angle)])
    assert np.max(np.linalg.norm(pivot, axis=1)) <= ARM * amplitude**2


def test_cli_animates_a_mode_and_refuses_one_the_model_has_not(tmp_path, capsys):
    model_file = tmp_path / "rod.yaml"
    model_file.write_text(HANGING_ROD)
    assert main(["run", str(model_file), "--out", str(tmp_path / "run")]) == 0
    results = tmp_path / "run" / "results.csv"
    assert main(["animate", str(model_file), str(results), "--mode", "1", "--no-vtk",
                 "--cycles", "1", "-o", str(tmp_path / "anim")]) == 0
    assert (tmp_path / "anim" / "animation.html").is_file()
    assert "49 frames" in capsys.readouterr().out  # one cycle of 48 frames and its end
    assert main(["animate", str(model_file), str(results), "--mode", "2", "--no-vtk"]) == 2
    assert "the model has 1 mode" in capsys.readouterr().err


def test_mode_of_a_run_without_a_linear_model_is_a_usage_error(tmp_path, capsys):
    """A dynamics run's folder has no linear_model.npz: a hint to run the modal analysis."""
    with pytest.raises(UsageError, match="--analysis modal"):
        read_linear_model(tmp_path / "linear_model.npz")
    (tmp_path / "linear_model.npz").write_text("not an archive")
    with pytest.raises(UsageError, match="not a linear model"):
        read_linear_model(tmp_path / "linear_model.npz")
