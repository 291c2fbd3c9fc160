"""casmech sweep (cli/sweep.py): the files it writes, --full, Ctrl-C, and a start-up that
does not import Dask for other commands."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd

from casmech import cli
from casmech.study.full import read_run
from casmech.study.sweep import parquet_available
from tests.conftest import ROOT
from tests.helpers.study import PENDULUM, SPRING_MASS


def test_files_and_full_results(tmp_path):
    out = tmp_path / "study"
    argv = ["sweep", str(SPRING_MASS), "--out", str(out), "--samples", "3", "--normal",
            "m=2,0.1", "--seed", "5", "--keep", "max(block.z)", "--keep", "final(block.vz)",
            "--keep", "integral(block.z)", "--workers", "0", "--full", "--set", "k=150"]
    assert cli.main(argv) == 0
    table = pd.read_csv(out / "sweep.csv", keep_default_na=False)
    assert list(table.columns) == ["run", "m", "status", "wall_s", "max(block.z)",
                                   "final(block.vz)", "integral(block.z)", "reason"]
    assert list(table["status"]) == ["complete"] * 3
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["study"]["seed"] == 5 and meta["study"]["samples"] == 3
    assert meta["study"]["distributions"] == {"m": {"kind": "normal", "mean": 2.0,
                                                    "sigma": 0.1}}
    assert meta["overrides"] == {"k": "150"} and len(meta["model"]["sha256"]) == 64
    assert meta["study"]["parquet"] == parquet_available()
    assert (out / "sweep.parquet").exists() == parquet_available()
    for run in range(3):  # the kept outputs are those of the run's whole table in runs.h5
        names, values, attrs = read_run(out / "runs.h5", run)
        assert attrs["m"] == table["m"][run] and attrs["status"] == "complete"
        assert values[:, names.index("block.z")].max() == table["max(block.z)"][run]
        assert values[-1, names.index("block.vz")] == table["final(block.vz)"][run]
        t, z = values[:, 0], values[:, names.index("block.z")]
        np.testing.assert_allclose(table["integral(block.z)"][run], np.trapezoid(z, t),
                                   rtol=1e-13, atol=1e-17)  # the same sum, other order


def test_usage_errors_exit_2(tmp_path, capsys):
    assert cli.main(["sweep", str(PENDULUM), "--grid", "L", "--workers", "0"]) == 2
    assert "--grid expects NAME=VALUES, got 'L'" in capsys.readouterr().err
    assert cli.main(["sweep", str(PENDULUM), "--out", str(tmp_path), "--grid", "L=1:2:x",
                     "--workers", "0"]) == 2
    assert "error[E409] --grid L: range '1:2:x'" in capsys.readouterr().err
    assert cli.main(["sweep", str(SPRING_MASS), "--workers", "0"]) == 2  # no study: no block
    assert "error[E409] --samples: the study names no parameter" in capsys.readouterr().err


def test_ctrl_c_keeps_the_finished_runs(tmp_path):
    out = tmp_path / "study"
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    process = subprocess.Popen(
        [sys.executable, "-m", "casmech.cli", "sweep", str(SPRING_MASS), "--out", str(out),
         "--samples", "2000", "--normal", "m=2,0.1", "--keep", "max(block.z)", "--workers",
         "0"], env=env, stderr=subprocess.PIPE, text=True)
    assert process.stderr.readline().startswith("sweep: 2000 runs")
    time.sleep(1.5)  # some runs finish (about 30 ms each)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130, err
    table = pd.read_csv(out / "sweep.csv")
    assert 0 < len(table) < 2000 and list(table["run"]) == list(range(len(table)))
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "interrupted" and meta["study"]["finished_runs"] == len(table)


def test_other_commands_do_not_import_dask():
    code = ("import sys; from casmech import cli; cli.main(['check', sys.argv[1]]); "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('dask', 'distributed', 'casmech.study')))")
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    shown = subprocess.run([sys.executable, "-c", code, str(PENDULUM)], env=env,
                           capture_output=True, text=True, check=True)
    assert shown.stdout.strip().splitlines()[-1] == "[]"
