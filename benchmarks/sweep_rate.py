"""Runs per second of `casmech sweep` (issue 18), printed as Markdown with machine, date, commit.

    python benchmarks/sweep_rate.py                 # pendulum and four-bar, 0/1/2/cores workers
    python benchmarks/sweep_rate.py --runs 40 --big 400 --repeats 3

For each model: a grid of --runs points run in this process (workers 0) and on local Dask
clusters of 1, 2 and the machine's workers (each the median of --repeats studies on one cluster;
its start-up and a first warm-up study are timed separately, not counted in the rate); the
per-run overhead
against one `casmech run` of the same model (a new process, as a user runs it, and the same
run in a warm process); and the time of a 10,000-run study of the pendulum on the machine's
workers, run in full with --big 10000 or estimated from --big runs (say which).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import casmech  # noqa: E402
from casmech.study import execute  # noqa: E402
from casmech.study import sweep as study  # noqa: E402

# name -> (model, grid parameter, its values as a range text with {n} points, kept, settings)
MODELS = {
    "pendulum": (ROOT / "tests" / "helpers" / "study_models" / "pendulum.yaml", "L", "0.5:2:{n}",
                 ["crossing(bob.y)"], {}),
    "four_bar": (ROOT / "models" / "four_bar.yaml", "a", "0.4:0.6:{n}",
                 ["max(rocker.wz)"], {}),
}


def study_rate(model: str, runs: int, workers: int, repeats: int) -> tuple[float, float]:
    """(median runs per second, start-up [s]) of a study of `runs` points. On a cluster the
    start-up is the cluster's start plus a first, untimed study (each worker process imports
    casmech and CasADi on its first task, about 1.5 s); the studies timed after it reuse the
    cluster."""
    path, name, values, keep, settings = MODELS[model]
    prepared = study.prepare(path, {"grid": {name: values.format(n=runs)}, "keep": keep},
                             settings)

    def timed(**where) -> float:
        clock = time.perf_counter()
        rows, _ = study.collect(prepared, **where)
        return len(rows) / (time.perf_counter() - clock)

    if workers == 0:
        return statistics.median(timed(workers=0) for _ in range(repeats)), 0.0
    clock = time.perf_counter()
    with execute.client(workers, None) as connected:
        connected.wait_for_workers(workers)
        address = connected.scheduler.address
        timed(scheduler=address)  # warm-up
        start = time.perf_counter() - clock
        return statistics.median(timed(scheduler=address) for _ in range(repeats)), start


def single_run(model: str, repeats: int) -> tuple[float, float]:
    """(median wall time of `casmech run` in a new process, of the same run in this one) [s]."""
    path, _, _, _, settings = MODELS[model]
    cli, warm = [], []
    with tempfile.TemporaryDirectory() as out:
        for _ in range(repeats):
            clock = time.perf_counter()
            subprocess.run([sys.executable, "-m", "casmech.cli", "run", str(path), "--out", out,
                            "--mode", "interpreted"], check=True, capture_output=True,
                           env={**os.environ, "PYTHONPATH": str(ROOT / "src")})
            cli.append(time.perf_counter() - clock)
    for _ in range(repeats + 1):
        clock = time.perf_counter()
        functions = casmech.compile(casmech.load(path), "interpreted")  # a run on its own
        casmech.results_table(functions, casmech.analyze(functions, **settings))
        warm.append(time.perf_counter() - clock)
    return statistics.median(cli), statistics.median(warm[1:])


def header() -> str:
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    when = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return (f"machine: {platform.node()}, {os.cpu_count()} cores, {platform.processor() or '?'}; "
            f"Python {platform.python_version()}; {when}; commit {commit}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=40, help="points per timed study")
    parser.add_argument("--repeats", type=int, default=3, help="studies per setting (median)")
    parser.add_argument("--big", type=int, default=400,
                        help="runs of the pendulum study scaled to 10,000 (10000: all of them)")
    args = parser.parse_args(argv)
    cores = os.cpu_count() or 1
    counts = sorted({0, 1, 2, cores})
    print(header(), "\n")
    print("| model | " + " | ".join(f"runs/s, {w} workers" for w in counts)
          + " | start + warm-up [s] | `casmech run` [s] | warm run [s] | sweep s/run, 0 workers |")
    print("|---" * (len(counts) + 5) + "|")
    for model in MODELS:
        measured = {w: study_rate(model, args.runs, w, args.repeats) for w in counts}
        cli, warm = single_run(model, args.repeats)
        start = max(s for _, s in measured.values())
        print(f"| {model} | " + " | ".join(f"{measured[w][0]:.1f}" for w in counts)
              + f" | {start:.2f} | {cli:.2f} | {warm:.3f} | {1 / measured[0][0]:.3f} |")
    rate, start = study_rate("pendulum", args.big, cores, 1)
    minutes = (10_000 / rate + start) / 60  # start includes a warm-up study of args.big runs
    how = "measured" if args.big >= 10_000 else f"estimated from {args.big} runs"
    print(f"\n10,000-run pendulum study on {cores} workers: {minutes:.1f} min ({how}; "
          f"{rate:.1f} runs/s, cluster start {start:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
