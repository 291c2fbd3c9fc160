"""A sweep's Dask cluster is its user's alone, a sweep keeps its finished runs whatever stops
it, and careless study options are refused at once (issue 35 items 2, 7, 15, 16).

- The local cluster listens on loopback only, speaks TLS with temporary credentials: another
  local client (a process without them) cannot connect, so a task it submits never runs,
  while the sweep's own client runs the same task (the control). No HTTP route is served
  unless --dashboard.
- A sweep killed with SIGKILL keeps every run it finished in sweep.csv; --resume runs only the
  others and gives the rows a whole sweep gives.
- --grid COUNT above the study limit is refused before any value is made; with two grids the
  message names --grid; a bad --scheduler is a one-line usage error within seconds."""

import json
import os
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request

import pandas as pd
import psutil
import pytest

import casmech
from casmech import cli
from casmech.study import execute
from tests.conftest import ROOT
from tests.helpers.study import PENDULUM, SPRING_MASS

pytest.importorskip("distributed")
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "src")}

INTRUDER = """
import sys
from distributed import Client
address, marker = sys.argv[1], sys.argv[2]

def plant(path):
    open(path, "w").write("ran")
    return "ran"

for attempt in (address, address.replace("tls://", "tcp://")):
    try:
        with Client(attempt, timeout=3) as client:
            print("SUBMITTED", client.submit(plant, marker).result(timeout=10))
    except Exception as error:  # what the intruder sees
        print("REFUSED", type(error).__name__)
"""


def _plant(path):
    with open(path, "w") as handle:
        handle.write("ran")
    return "ran"


def _listening(process: psutil.Process) -> set[str]:
    found = set()
    for each in [process, *process.children(recursive=True)]:
        try:
            found |= {c.laddr.ip for c in each.net_connections(kind="inet")
                      if c.status == psutil.CONN_LISTEN}
        except psutil.NoSuchProcess:
            pass
    return found


def test_another_local_client_cannot_submit_to_the_sweeps_cluster(tmp_path):
    marker = tmp_path / "marker"
    with execute.client(1, None) as connected:
        address = connected.scheduler.address
        assert address.startswith("tls://127.0.0.1:")
        assert all(w.startswith("tls://127.0.0.1:") for w in connected.scheduler_info()["workers"])
        assert _listening(psutil.Process()) <= {"127.0.0.1"}  # nothing on another interface
        done = subprocess.run([sys.executable, "-c", INTRUDER, address, str(marker)], env=ENV,
                              capture_output=True, text=True, timeout=120)
        assert done.stdout.count("REFUSED") == 2 and "SUBMITTED" not in done.stdout, \
            done.stdout + done.stderr[-2000:]
        assert not marker.exists()
        port = connected.cluster.scheduler.http_server.port
        with pytest.raises(urllib.error.HTTPError, match="404"):  # no dashboard, no metrics
            urllib.request.urlopen(f"http://127.0.0.1:{port}/status", timeout=5)
        # the control: with the credentials, the same task runs (and writes the marker)
        assert connected.submit(_plant, str(marker)).result(timeout=60) == "ran"
    assert marker.read_text() == "ran"


def test_the_dashboard_only_when_asked_and_on_loopback():
    with execute.client(1, None, dashboard=True) as connected:
        link = connected.dashboard_link
        assert link.startswith("http://127.0.0.1:")
        assert urllib.request.urlopen(link, timeout=10).status == 200


@pytest.mark.parametrize("address", ["localhost", "tcp://127.0.0.1:notaport",
                                     "http://127.0.0.1:8786", "tls://host:8786 x"])
def test_a_scheduler_address_of_the_wrong_form_is_a_usage_error(address, capsys, monkeypatch):
    def never(*args, **kwargs):
        raise AssertionError("the model was loaded before the address was checked")

    monkeypatch.setattr("casmech.schema.load_model", never)  # refused before the model is loaded
    assert cli.main(["sweep", str(PENDULUM), "--grid", "L=1,2", "--scheduler", address]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is not a Dask scheduler's address" in err


def test_a_scheduler_that_does_not_answer_is_a_usage_error_within_seconds(tmp_path):
    clock = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "casmech.cli", "sweep", str(PENDULUM),
                           "--grid", "L=1,2", "--scheduler", "tcp://127.0.0.1:1",
                           "--out", str(tmp_path / "study")], env=ENV,
                          capture_output=True, text=True, timeout=120)
    seconds = time.perf_counter() - clock
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("casmech:")]
    assert len(errors) == 1 and "no Dask scheduler answered within 5s" in errors[0]
    assert seconds < 20  # start-up and the 5 s connection timeout; it took 30 s and a traceback
    # metadata.json says so, not "running": status failed, the error's text
    metadata = json.loads((tmp_path / "study" / "metadata.json").read_text())
    assert metadata["status"] == "failed" and "no Dask scheduler answered" in metadata["error"]
    assert metadata["rows"] == 0 and metadata["study"]["runs"] == 2


@pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="needs Linux's /proc")
def test_a_huge_grid_is_refused_before_it_is_made():
    """The process's peak memory (VmHWM: this process's own, not inherited as ru_maxrss is
    across exec) stays that of its imports; the grid alone would take 800 MB."""
    code = ("import re, sys; from casmech import cli; "
            "status = cli.main(sys.argv[1:]); "
            "peak = re.search(r'VmHWM:\\s+(\\d+)', open('/proc/self/status').read()).group(1); "
            "print(status, peak)")
    done = subprocess.run([sys.executable, "-c", code, "sweep", str(PENDULUM), "--grid",
                           "L=0.4:0.6:100000000", "--workers", "0"], env=ENV,
                          capture_output=True, text=True, timeout=120)
    status, peak_kb = (int(n) for n in done.stdout.split())
    assert status == 2 and "100000000 values, more than a study's 10000000 runs" in done.stderr
    assert peak_kb < 400_000  # imports and the model: ~150 MB


def test_two_grids_too_large_name_the_grid(capsys):
    assert cli.main(["sweep", str(PENDULUM), "--grid", "L=0.4:0.6:5000", "--grid",
                     "m=1:2:5000", "--workers", "0"]) == 2
    err = capsys.readouterr().err
    assert "error[E409] --grid: the study has 25000000 runs (5000 x 5000)" in err
    assert "--samples" not in err


STUDY = ["--samples", "120", "--normal", "m=2,0.1", "--seed", "4", "--keep", "max(block.z)",
         "--keep", "final(block.vz)"]


def test_a_killed_sweep_keeps_its_runs_and_resume_completes_it(tmp_path):
    """(--mode interpreted: every process of the study runs the same code whatever the cache
    holds; under auto a process finding the library runs compiled, and method auto there
    DOP853 where the interpreted runs take Adams, docs/decisions/method-auto.md.)"""
    killed, whole = tmp_path / "killed", tmp_path / "whole"
    command = [sys.executable, "-m", "casmech.cli", "sweep", str(SPRING_MASS), *STUDY,
               "--workers", "0", "--mode", "interpreted"]
    process = subprocess.Popen([*command, "--out", str(killed)], env=ENV,
                               stderr=subprocess.DEVNULL)
    results = killed / "sweep.csv"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:  # until a few runs are in
        if results.exists() and len(results.read_text().splitlines()) > 6:
            break
        time.sleep(0.02)
    process.send_signal(signal.SIGKILL)
    process.wait(timeout=30)
    kept = pd.read_csv(results)
    assert 5 <= len(kept) < 120 and set(kept["status"]) == {"complete"}
    assert json.loads((killed / "metadata.json").read_text())["status"] == "running"

    done = subprocess.run([*command, "--out", str(killed), "--resume"], env=ENV,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert f"{len(kept)} finished earlier" in done.stderr
    assert cli.main(["sweep", str(SPRING_MASS), *STUDY, "--workers", "0", "--mode",
                     "interpreted", "--out", str(whole)]) == 0
    resumed, fresh = pd.read_csv(results), pd.read_csv(whole / "sweep.csv")
    assert list(resumed["run"]) == list(range(120))
    # deterministic runs: the same doubles, whether run before the kill, after it or at once
    pd.testing.assert_frame_equal(resumed.drop(columns="wall_s"), fresh.drop(columns="wall_s"),
                                  check_exact=True)
    earlier = resumed.set_index("run").loc[kept["run"], "wall_s"].to_numpy()
    assert (earlier == kept["wall_s"].to_numpy()).all()  # those runs were not run again
    assert json.loads((killed / "metadata.json").read_text())["status"] == "complete"


def test_resume_refuses_another_studys_file(tmp_path, capsys):
    out = tmp_path / "study"
    assert cli.main(["sweep", str(SPRING_MASS), "--samples", "3", "--normal", "m=2,0.1",
                     "--keep", "max(block.z)", "--workers", "0", "--out", str(out)]) == 0
    assert cli.main(["sweep", str(SPRING_MASS), "--samples", "3", "--normal", "m=2,0.1",
                     "--seed", "9", "--keep", "max(block.z)", "--workers", "0", "--out",
                     str(out), "--resume"]) == 2
    assert "run 0 has other parameter values than this study's" in capsys.readouterr().err
    assert cli.main(["sweep", str(SPRING_MASS), "--samples", "3", "--normal", "m=2,0.1",
                     "--keep", "min(block.z)", "--workers", "0", "--out", str(out),
                     "--resume"]) == 2
    assert "is not this study's results file (its columns differ" in capsys.readouterr().err


def test_sigterm_stops_a_dask_sweep_promptly_keeping_its_runs(tmp_path):
    out = tmp_path / "study"
    process = subprocess.Popen(
        [sys.executable, "-m", "casmech.cli", "sweep", str(SPRING_MASS), "--out", str(out),
         "--samples", "3000", "--normal", "m=2,0.1", "--keep", "max(block.z)", "--workers",
         "1"], env=ENV, stderr=subprocess.PIPE, text=True)
    results = out / "sweep.csv"
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline:
        if results.exists() and len(results.read_text().splitlines()) > 3:
            break
        time.sleep(0.05)
    clock = time.monotonic()
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    seconds = time.monotonic() - clock
    assert process.returncode == 130, err
    assert seconds < 15, seconds  # the cluster's shutdown included
    table = pd.read_csv(results)
    assert 3 <= len(table) < 3000 and list(table["run"]) == sorted(table["run"])
    assert json.loads((out / "metadata.json").read_text())["status"] == "interrupted"


def test_a_study_that_stops_on_an_error_keeps_its_rows_and_says_failed(tmp_path, monkeypatch):
    """An error out of the runs' executor after some runs finished (a worker lost, a scheduler
    gone): the error reaches the caller, sweep.csv keeps the finished runs, metadata.json says
    failed with the error's text and that many rows (study.sweep.run)."""
    original = execute.execute

    def failing(job, points, done, *args, **kwargs):
        original(job, points[:1], done, 0)  # the first run, in this process
        raise RuntimeError("the scheduler went away")

    monkeypatch.setattr(execute, "execute", failing)
    out = tmp_path / "study"
    with pytest.raises(RuntimeError, match="went away"):
        casmech.sweep(PENDULUM, grid={"L": [1.0, 2.0]}, keep=["crossing(bob.y)"], workers=0,
                      out=out)
    assert len(pd.read_csv(out / "sweep.csv")) == 1
    metadata = json.loads((out / "metadata.json").read_text())
    assert (metadata["status"], metadata["error"], metadata["rows"]) == (
        "failed", "the scheduler went away", 1)
