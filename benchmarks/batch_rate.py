"""Runs per second of a batched parameter study (issue 36): the gallery pendulum
(models/pendulum.yaml) over a length grid, its periods against the exact ones, printed as
Markdown with machine, date and commit.

    python benchmarks/batch_rate.py                      # 10,000 runs, 3 repeats
    python benchmarks/batch_rate.py --runs 2000 --repeats 1 --no-dask --no-process

Rows (the model's library built once before, in a private cache, not timed):
- `casmech.sweep(..., grid L=0.5:2:RUNS)`, the default (auto: batched, in this process on
  every core), the whole call (prepare, runs, table) in a warm process;
- the same on a local Dask cluster of 2 workers (`workers=2`; the cluster's start and its
  workers' first batch are in the time);
- `casmech sweep models/pendulum.yaml --grid L=0.5:2:RUNS` as a whole process (imports,
  sweep.csv and metadata.json written);
- run by run on the same library (`mode="compiled", workers=0`, 200 runs), the way a compiled
  study ran before batches.
The largest |4 crossing(bob.y) - T| over the batched study, T = 4 sqrt(I_O/(m g L)) K(k).
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

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODEL = ROOT / "models" / "pendulum.yaml"


def exact_period(L: np.ndarray, theta0: float = 1.0, r: float = 0.05, rho: float = 7800.0):
    from scipy.special import ellipk

    m = rho * 4 / 3 * np.pi * r**3
    inertia = 2 / 5 * m * r**2 + m * L**2
    return 4 * np.sqrt(inertia / (m * 9.81 * L)) * ellipk(np.sin(theta0 / 2) ** 2)


def timed_sweep(runs: int, **options) -> tuple[float, object]:
    import casmech

    clock = time.perf_counter()
    table = casmech.sweep(MODEL, grid={"L": f"0.5:2:{runs}"}, **options)
    return time.perf_counter() - clock, table


def process(runs: int, out: Path) -> float:
    clock = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import sys; from casmech.cli import main; "
                    "sys.exit(main())", "sweep", str(MODEL), "--grid", f"L=0.5:2:{runs}",
                    "--out", str(out)], check=True, capture_output=True,
                   env={**os.environ, "PYTHONPATH": str(ROOT / "src")})
    return time.perf_counter() - clock


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-dask", action="store_true")
    parser.add_argument("--no-process", action="store_true")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT / "src"))
    with tempfile.TemporaryDirectory(prefix="batch-rate-") as folder:
        os.environ["CASMECH_CACHE_DIR"] = str(Path(folder) / "cache")
        timed_sweep(8, mode="batched", workers=0)  # builds the library (not timed)
        rows = []
        walls = []
        for _ in range(args.repeats):
            wall, table = timed_sweep(args.runs)
            walls.append(wall)
        assert set(table["status"]) == {"complete"}, table["status"].value_counts()
        error = np.max(np.abs(4 * table["crossing(bob.y)"].to_numpy()
                              - exact_period(table["L"].to_numpy())))
        wall = statistics.median(walls)
        rows.append(("`casmech.sweep`, default (batched, this process)", wall, args.runs))
        if not args.no_dask:
            wall, _ = timed_sweep(args.runs, workers=2)
            rows.append(("`casmech.sweep(..., workers=2)` (Dask, batched tasks)", wall,
                         args.runs))
        if not args.no_process:
            wall = statistics.median(process(args.runs, Path(folder) / f"out{k}")
                                     for k in range(args.repeats))
            rows.append(("`casmech sweep` whole process", wall, args.runs))
        single = statistics.median(timed_sweep(200, mode="compiled", workers=0)[0]
                                   for _ in range(args.repeats))
        rows.append(("run by run on the library (`mode=\"compiled\", workers=0`)", single, 200))
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"{platform.node()}, {os.cpu_count()} cores; Python {platform.python_version()}; "
          f"{datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC; commit {commit}; load {load} at "
          f"the end; medians of {args.repeats}\n")
    print("| study | runs | wall [s] | runs/s |")
    print("|---|---:|---:|---:|")
    for label, wall, runs in rows:
        print(f"| {label} | {runs} | {wall:.2f} | {runs / wall:.0f} |")
    print(f"\nlargest |4 crossing(bob.y) - T_exact| over the batched study: {error:.2e} s")


if __name__ == "__main__":
    main()
