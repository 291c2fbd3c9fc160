"""Time per stage from YAML to a ready model and its initial state, for N-link spherical chains
(benchmarks/systems.py chain(N)); issue 21: a 1000-link chain within 2 minutes, growing ~N.

    python benchmarks/scaling.py                          # N = 8 32 128 256 512 1000, interpreted
    python benchmarks/scaling.py --n 8 32 --repeats 3 --mode compiled

Stages, each timed on its own (CPU and wall seconds, medians over --repeats, a fresh process
per N so that one size's memory does not slow the next):
- load: casmech.loads of the YAML text (validation, evaluation);
- build: casmech.compile (interpreted: the SX functions; compiled: C generated, built and
  loaded, with a private empty cache per repeat, so the build is measured);
- initial_state: runtime.assembly.initial_state (Newton assembly from the file's pose and the
  file's velocities projected onto the constraints);
- structure: compiler.checks.structure at the assembled pose (rank, redundant rows);
- total: the sum.
"""

from __future__ import annotations

import argparse
import json
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
STAGES = ("load", "build", "initial_state", "structure")


def one_size(n: int, repeats: int, mode: str) -> dict:
    """Medians of each stage for chain(n) (runs in the child process)."""
    sys.path[:0] = [str(ROOT / "src"), str(ROOT / "benchmarks")]
    from casmech_model import yaml_text
    from systems import chain

    import casmech
    from casmech.compiler.checks import structure
    from casmech.runtime import assembly

    text = yaml_text(chain(n))
    samples: dict[str, list[tuple[float, float]]] = {stage: [] for stage in STAGES}

    def timed(stage, run):
        wall, cpu = time.perf_counter(), time.process_time()
        value = run()
        samples[stage].append((time.perf_counter() - wall, time.process_time() - cpu))
        return value

    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as cache:
            os.environ["CASMECH_CACHE_DIR"] = cache
            model = timed("load", lambda: casmech.loads(text))
            functions = timed("build", lambda model=model: casmech.compile(model, mode))
            q, _ = timed("initial_state", lambda f=functions: assembly.initial_state(f))
            report = timed("structure", lambda f=functions, q=q: structure(f, 0.0, q))
    assert report.dof == 3 * n and report.rank == report.n_rows, report.summary()
    return {stage: [statistics.median(s[k] for s in samples[stage]) for k in (0, 1)]
            for stage in STAGES}


def header() -> str:
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "src"],
                           capture_output=True, text=True).stdout.strip()
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    return (f"{datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC, commit {commit}"
            f"{' + uncommitted src' if dirty else ''}, {platform.node()} "
            f"({platform.machine()}, {os.cpu_count()} cores), load {load}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", nargs="+", type=int, default=[8, 32, 128, 256, 512, 1000])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--mode", choices=("interpreted", "compiled"), default="interpreted")
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child is not None:
        print(json.dumps(one_size(args.child, args.repeats, args.mode)))
        return
    print(header(), f"mode {args.mode}, medians of {args.repeats}; seconds CPU (wall)\n")
    print("| N | " + " | ".join(STAGES) + " | total |")
    print("|---:|" + "---:|" * (len(STAGES) + 1))
    for n in args.n:
        done = subprocess.run([sys.executable, __file__, "--child", str(n), "--repeats",
                               str(args.repeats), "--mode", args.mode],
                              capture_output=True, text=True, check=False)
        if done.returncode != 0:
            print(f"| {n} | failed: {done.stderr.strip().splitlines()[-1]} |")
            continue
        stages = json.loads(done.stdout.strip().splitlines()[-1])
        cells = [f"{cpu:.3g} ({wall:.3g})" for wall, cpu in stages.values()]
        wall = sum(w for w, _ in stages.values())
        cpu = sum(c for _, c in stages.values())
        print(f"| {n} | " + " | ".join(cells) + f" | {cpu:.3g} ({wall:.3g}) |", flush=True)


if __name__ == "__main__":
    main()
