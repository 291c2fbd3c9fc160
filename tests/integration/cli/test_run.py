"""casmech run's --reactions-frame (cli/run.py): the reaction columns of every joint in
the frame asked for, as the Python API gives them, metadata.json naming each joint's frame, and
--replay repeating it."""

import json

import numpy as np

import casmech
from casmech import cli
from casmech.io.csv import read_csv
from tests.conftest import MODELS

SLIDER = MODELS / "slider_crank.yaml"  # revolute, spherical, universal, translational


def test_reactions_frame_flag_writes_every_joint_in_that_frame(tmp_path):
    out = tmp_path / "run"
    argv = ["run", str(SLIDER), "--out", str(out), "--t-end", "0.2", "--mode", "interpreted",
            "--reactions-frame", "body_j"]
    assert cli.main(argv) == 0
    names, values = read_csv(out / "results.csv")
    functions = casmech.compile(casmech.load(SLIDER), "interpreted")
    result = casmech.analyze(functions, t_end=0.2)
    expected_names, expected = casmech.results_table(functions, result, "body_j")
    _, in_global = casmech.results_table(functions, result)
    assert names == expected_names  # the contract's column names, unchanged
    # the same computation, written as text with 17 significant digits and read back
    np.testing.assert_allclose(values, expected, rtol=1e-15, atol=1e-300)
    assert not np.allclose(values, in_global)  # the flag changed the reaction columns
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["reaction_frames"] == {
        "crank_pivot": {"frame": "body_j", "body": "crank"},
        "crank_pin": {"frame": "body_j", "body": "rod"},
        "wrist_pin": {"frame": "body_j", "body": "rod"},
        "slide": {"frame": "body_j", "body": "slider"},
    }
    assert meta["options"]["reactions_frame"] == "body_j"
    assert cli.main(["run", "--replay", str(out / "metadata.json")]) == 0
    replay_names, replay_values = read_csv(tmp_path / "run_replay" / "results.csv")
    np.testing.assert_array_equal(replay_values, values)  # the same code on the same inputs


def test_without_the_flag_the_files_frames_are_used(tmp_path):
    text = SLIDER.read_text(encoding="utf-8").replace(
        "    axis: [1, 0, 0]\n", "    axis: [1, 0, 0]\n    reactions: {frame: joint}\n")
    (tmp_path / "slider.yaml").write_text(text)
    out = tmp_path / "run"
    assert cli.main(["run", str(tmp_path / "slider.yaml"), "--out", str(out), "--t-end", "0.2",
                     "--mode", "interpreted"]) == 0
    names, values = read_csv(out / "results.csv")
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["reaction_frames"]["slide"]["frame"] == "joint"
    assert meta["reaction_frames"]["crank_pivot"] == {"frame": "global"}
    assert "reactions_frame" not in meta["options"]
    # the slide (axis x) carries no force along its axis: its joint-frame fz (w = x) is zero
    # while its lateral force is not (roundoff of multipliers of size ~10: 1e-12)
    np.testing.assert_allclose(values[:, names.index("slide.fz")], 0.0, rtol=0, atol=1e-12)
    assert np.max(np.abs(values[:, names.index("slide.fy")])) > 1.0
