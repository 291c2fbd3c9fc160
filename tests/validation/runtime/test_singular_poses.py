"""Singular poses passed during a run (runtime/singular_poses.py), against IFToMM A02's exact
solution: its cranks are flat (sin(phi) = 0) at known times."""

import json

import numpy as np

import casmech
from casmech.cli import main
from tests.conftest import MODELS
from tests.helpers.reference_data import read_analytic
from tests.validation.runtime.test_validation_iftomm import A02


def flat_times(t_end: float) -> np.ndarray:
    """Where the exact crank angle passes a multiple of pi (linear interpolation)."""
    exact = read_analytic("A02_Nfourbar_N2_0-10s.csv")
    t, s = exact["t"], np.sin(exact["phi"])
    k = np.flatnonzero(np.sign(s[1:]) != np.sign(s[:-1]))
    crossings = t[k] - s[k] * (t[k + 1] - t[k]) / (s[k + 1] - s[k])
    return crossings[crossings < t_end]


def test_a02_reports_each_flat_pose_at_its_time_with_its_joints():
    functions = casmech.compile(casmech.load(A02))
    # rtol 1e-7: the flat poses' times come out the same as at 1e-8 (within half the output
    # step of the exact ones); the check is where they are reported, not the motion's accuracy
    result = casmech.analyze(functions, "dynamics", t_end=3.5, rtol=1e-7, atol=1e-9)
    poses = result.metadata["singular_poses"]
    expected = flat_times(3.5)
    assert len(expected) == 4 and len(poses) == len(expected)
    # the output row nearest each exact flat pose (output step 0.01 s)
    np.testing.assert_allclose([p["t"] for p in poses], expected, rtol=0, atol=0.01)
    for pose in poses:
        assert pose["smallest_singular_value"] < 1e-2  # against ~0.2 away from the poses
        # the dependency is the middle crank's revolute rows (b1, split in two in the file)
        assert {"b1_left", "b1_right"} <= set(pose["joints"])
        assert all(source.startswith(str(A02)) for source in pose["sources"][:2])


def test_loops_away_from_singular_poses_and_trees_report_none():
    bricard = casmech.compile(casmech.load(MODELS / "bricard.yaml"))
    assert casmech.analyze(bricard, "dynamics", t_end=0.5).metadata["singular_poses"] == []
    tree = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    assert "singular_poses" not in casmech.analyze(tree, "dynamics", t_end=0.1).metadata


def test_cli_warns_and_records_them(tmp_path, capsys):
    assert main(["run", str(A02), "--t-end", "1", "--rtol", "1e-8", "--atol", "1e-10",
                 "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    assert "warning: near a singular pose at t = 0.71 " in err
    assert "b1_left (" in err
    # auto tried joint coordinates first and says why it ran rp
    assert "note: formulation auto ran the model again in rp: joint coordinates went near a " \
           "singular pose at t = 0.71" in err
    metadata = json.loads((tmp_path / "metadata.json").read_text())
    assert [round(p["t"], 2) for p in metadata["result"]["singular_poses"]] == [0.71]
    assert metadata["result"]["formulation"] == "rp"
    assert "formulation_fallback" in metadata["result"]
