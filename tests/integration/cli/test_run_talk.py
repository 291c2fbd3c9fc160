"""What `casmech run` prints: --quiet (errors only), --verbose (stages, solver messages, every
singular pose), and repeated singular-pose warnings folded into one line per set of joints
with the count and times (IFToMM A02's cranks go flat at known times: four in 3.5 s, two about
each of two pairs of joints)."""

import json

import pytest

from casmech.cli import main
from casmech.cli.run import singular_pose_warnings
from tests.conftest import MODELS
from tests.validation.runtime.test_singular_poses import flat_times
from tests.validation.runtime.test_validation_iftomm import A02

FOUR_BAR = MODELS / "four_bar.yaml"


def pose(t, joints, value):
    return {"t": t, "smallest_singular_value": value, "joints": joints,
            "sources": [f"m.yaml:{k}:5" for k in range(len(joints))]}


def test_poses_about_the_same_joints_fold_into_one_line():
    poses = [pose(0.7, ["a", "b"], 3e-3), pose(1.2, ["c", "b"], 2e-3),
             pose(2.6, ["a", "b"], 7e-4), pose(4.6, ["a", "b"], 5e-3)]
    lines = singular_pose_warnings(poses)
    assert len(lines) == 2
    assert lines[0] == ("near a singular pose 3 times, at t = 0.7, 2.6, 4.6 s (smallest singular "
                        "value of the unit constraint rows down to 7.00e-04; --verbose lists "
                        "each): a (m.yaml:0:5), b (m.yaml:1:5)")
    assert lines[1].startswith("near a singular pose at t = 1.2 (smallest singular value "
                               "2.00e-03")  # alone: the line of singular_poses.describe
    assert len(singular_pose_warnings(poses, every=True)) == 4


def test_a02_warns_once_per_pair_of_joints(tmp_path, capsys):
    assert main(["run", str(A02), "--t-end", "3.5", "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    warnings = [line for line in err.splitlines() if line.startswith("warning:")]
    recorded = json.loads((tmp_path / "metadata.json").read_text())["result"]["singular_poses"]
    assert len(recorded) == len(flat_times(3.5)) == 4  # every pose stays in the metadata
    assert len(warnings) == 2 and all("2 times, at t = " in line for line in warnings)


def test_quiet_prints_nothing_and_verbose_more(tmp_path, capsys):
    assert main(["run", str(A02), "--t-end", "1", "--out", str(tmp_path / "q"), "-q"]) == 0
    out, err = capsys.readouterr()
    assert (out, err) == ("", "")
    metadata = json.loads((tmp_path / "q" / "metadata.json").read_text())
    assert metadata["result"]["singular_poses"]  # the warning's facts are kept
    assert main(["run", str(A02), "--t-end", "1", "--out", str(tmp_path / "v"),
                 "--verbose"]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("dynamics: 101 rows")
    assert "timings: load " in err and "compile " in err and "formulation rp" in err
    assert "warning: near a singular pose at t = 0.71 " in err


def test_quiet_still_reports_errors(tmp_path, capsys):
    code = main(["run", str(FOUR_BAR), "--out", str(tmp_path), "--quiet", "--t-end", "-1"])
    assert code == 2
    out, err = capsys.readouterr()
    assert out == "" and "error[E409] t_end = -1" in err


def test_quiet_and_verbose_exclude_each_other(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["run", str(FOUR_BAR), "--out", str(tmp_path), "-q", "-v"])
    assert stop.value.code == 2
    assert "not allowed with argument" in capsys.readouterr().err
