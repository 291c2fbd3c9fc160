"""casmech.study.execute: the same study in this process, on a local Dask cluster and on a
`distributed` scheduler with separate worker processes started here, gives identical rows."""

import os
import subprocess
import sys
import time

import pandas as pd
import pytest

import casmech
from casmech.study.execute import MAX_BATCH, TASKS_PER_WORKER, batch_size
from casmech.study.runner import Job, Outcome, Runner, run_batch
from tests.conftest import ROOT
from tests.helpers.study import FOUR_BAR

pytest.importorskip("distributed")
STUDY = {"grid": {"a": [0.45, 1.9, 0.55], "omega": [3.0, 4.0]},
         "keep": ["max(rocker.wz)", "crossing(rocker.wz)", "integral(crank.wz)"], "t_end": 0.4}


def same_rows(table, expected):
    """Equal bit for bit but the wall times (which differ from run to run); NaN equals NaN."""
    pd.testing.assert_frame_equal(table.drop(columns="wall_s"), expected.drop(columns="wall_s"),
                                  check_exact=True)


@pytest.fixture
def scheduler(tmp_path):
    """A scheduler and a worker process of two workers on localhost, as a user starts them."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    file = tmp_path / "scheduler.json"
    started = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler",
                                 "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                 "--scheduler-file", str(file)], env=env,
                                stderr=subprocess.DEVNULL)]
    try:
        for _ in range(300):
            if file.exists() and file.stat().st_size:
                break
            time.sleep(0.05)
        started.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", "--scheduler-file", str(file),
             "--nworkers", "2", "--nthreads", "1", "--no-dashboard"], env=env,
            stderr=subprocess.DEVNULL))
        import json

        address = json.loads(file.read_text())["address"]
        from distributed import Client

        with Client(address) as client:
            client.wait_for_workers(2, timeout=60)
        yield address
    finally:
        for process in reversed(started):
            process.terminate()
            process.wait(timeout=30)


def test_identical_rows_everywhere(scheduler):
    here = casmech.sweep(FOUR_BAR, workers=0, **STUDY)
    local = casmech.sweep(FOUR_BAR, workers=2, **STUDY)
    remote = casmech.sweep(FOUR_BAR, scheduler=scheduler, **STUDY)
    assert list(here["status"]) == ["complete"] * 2 + ["failed"] * 2 + ["complete"] * 2
    same_rows(local, here)
    same_rows(remote, here)


def test_batches_keep_workers_busy_and_bounded():
    assert batch_size(10_000, 2) == MAX_BATCH
    assert batch_size(40, 2) == 40 // (2 * TASKS_PER_WORKER)
    assert batch_size(5, 2) == 1 and batch_size(100, 0) == 100 // TASKS_PER_WORKER


def test_a_run_that_raises_fails_alone(monkeypatch):
    def run(self, values):
        if values["L"] == 2.0:
            raise ValueError("a bug\nsecond line")
        return Outcome(dict(values), "complete")

    monkeypatch.setattr(Runner, "run", run)
    outcomes = run_batch(Job("model.yaml", "", keep=("max(x.z)",)), [{"L": 1.0}, {"L": 2.0},
                                                                    {"L": 3.0}])
    assert [o.status for o in outcomes] == ["complete", "failed", "complete"]
    assert outcomes[1].reason == "ValueError: a bug | second line"
