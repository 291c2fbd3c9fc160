"""Time per stage from YAML to a ready model and its initial state, for N-link spherical chains
(benchmarks/systems.py chain(N)); issue 21: a 1000-link chain within 2 minutes, growing ~N.

    python benchmarks/scaling.py                          # N = 8 32 128 256 512 1000, interpreted
    python benchmarks/scaling.py --n 8 32 --repeats 3 --mode compiled

Stages, each timed on its own (CPU and wall seconds, medians over --repeats, a fresh process
per N so that one size's memory does not slow the next):
- load: casmech.loads of the YAML text (validation, evaluation);
- build: casmech.compile (interpreted: the bundle, whose SX functions are built when first
  used, so their cost falls in the stages that use them; compiled: C generated, built and
  loaded, with a private empty cache per repeat, so the build is measured);
- initial_state: runtime.assembly.initial_state (Newton assembly from the file's pose and the
  file's velocities projected onto the constraints);
- structure: equations.checks.structure at the assembled pose (rank, redundant rows);
- formulation: a first, 0.01 s analysis, which builds the default formulation's functions
  (joint coordinates for the chain: the tree's ODE and results rows);
- simulate: casmech.analyze(..., "dynamics") over --t-sim seconds from horizontal rest,
  output every 0.01 s, rtol 1e-8 (the integration and the results rows);
- total: the sum.

`--plot FILE.png` draws seconds per simulated second against N (log-log, with a line of
slope 1) from the simulate stage.
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
STAGES = ("load", "build", "initial_state", "structure", "formulation", "simulate")


def one_size(n: int, repeats: int, mode: str, t_sim: float) -> dict:
    """Medians of each stage for chain(n) (runs in the child process)."""
    sys.path[:0] = [str(ROOT / "src"), str(ROOT / "benchmarks")]
    from casmech_model import yaml_text
    from systems import T_END, chain

    import casmech
    from casmech.equations.checks import structure
    from casmech.runtime import assembly

    # the model's own span is the simulated one: its output grid (rows x results columns) is
    # bounded at load time (schema.limits.MAX_VALUES), which the 10 s default exceeds at N = 1000
    text = yaml_text(chain(n)).replace(f"t_end: {T_END!r}", f"t_end: {t_sim!r}")
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
            timed("formulation", lambda f=functions: casmech.analyze(
                f, "dynamics", t_end=0.01, output_step=0.01, rtol=1e-8, atol=1e-10))
            timed("simulate", lambda f=functions: casmech.analyze(
                f, "dynamics", t_end=t_sim, output_step=0.01, rtol=1e-8, atol=1e-10))
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
    parser.add_argument("--t-sim", type=float, default=1.0, help="simulated seconds")
    parser.add_argument("--plot", type=Path, help="PNG of seconds per simulated second vs N")
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child is not None:
        print(json.dumps(one_size(args.child, args.repeats, args.mode, args.t_sim)))
        return
    print(header(), f"mode {args.mode}, medians of {args.repeats}; seconds CPU (wall)\n")
    print("| N | " + " | ".join(STAGES) + " | total |")
    print("|---:|" + "---:|" * (len(STAGES) + 1))
    rates = {}
    for n in args.n:
        done = subprocess.run([sys.executable, __file__, "--child", str(n), "--repeats",
                               str(args.repeats), "--mode", args.mode, "--t-sim",
                               str(args.t_sim)], capture_output=True, text=True, check=False)
        if done.returncode != 0:
            print(f"| {n} | failed: {done.stderr.strip().splitlines()[-1]} |")
            continue
        stages = json.loads(done.stdout.strip().splitlines()[-1])
        cells = [f"{cpu:.3g} ({wall:.3g})" for wall, cpu in stages.values()]
        wall = sum(w for w, _ in stages.values())
        cpu = sum(c for _, c in stages.values())
        print(f"| {n} | " + " | ".join(cells) + f" | {cpu:.3g} ({wall:.3g}) |", flush=True)
        rates[n] = stages["simulate"][0] / args.t_sim
    if args.plot and rates:
        plot(rates, args.plot, header())


def plot(rates: dict[int, float], path: Path, title: str) -> None:
    """Seconds (wall) per simulated second against N, log-log, with a slope-1 guide."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = sorted(rates)
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.loglog(n, [rates[k] for k in n], "o-", label="casmech (joint coordinates, CVODES)")
    ax.loglog(n, [rates[n[0]] * k / n[0] for k in n], "--", color="gray",
              label="proportional to N")
    ax.set_xlabel("links N")
    ax.set_ylabel("wall seconds per simulated second")
    ax.set_title(f"N-link chain, rtol 1e-8\n{title}", fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    main()
