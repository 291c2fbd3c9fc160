"""`casmech run --set` on compiled models and a compiled sweep, two source trees side by side
(docs/decisions/joint-system-over-model-data.md): a tree (models/double_pendulum.yaml) and a
loop (the four-bar of models/four_bar.yaml without its driver, swinging under gravity).

    python benchmarks/jointparam_set.py --before /work/main/src --after src --repeats 3

Each tree runs with its own cache directory (built once by a first run, not timed); then the
runs alternate between the trees, each at new parameter values: the wall time of the CLI
process, the analysis time it records and the formulation it ran. The sweep: casmech.sweep in
one process (workers 0, mode compiled) over N values, its total wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def free_four_bar() -> str:
    text = (ROOT / "models" / "four_bar.yaml").read_text()
    text = text.replace("    driver:\n      angle: omega * t\n", "")
    text = text.replace("output_step: 0.01", "output_step: 0.01\n  rtol: 1.0e-8\n  atol: 1.0e-10")
    return text.replace("analysis:\n  type: inverse_dynamics",
                        "gravity: [0, -9.81, 0]\n\nanalysis:\n  type: dynamics")


MODELS = {"double_pendulum": ((ROOT / "models" / "double_pendulum.yaml").read_text(), "m1"),
          "four_bar": (free_four_bar(), "b")}


def environment(source: str, cache: Path) -> dict:
    return {**os.environ, "PYTHONPATH": str(Path(source).resolve()),
            "CASMECH_CACHE_DIR": str(cache)}


def run(env: dict, path: Path, name: str, value: float, out: Path) -> dict:
    clock = time.perf_counter()
    subprocess.run([sys.executable, "-m", "casmech.cli", "run", str(path), "--mode", "compiled",
                    "--set", f"{name}={value}", "--out", str(out)], env=env, check=True,
                   capture_output=True)
    wall = time.perf_counter() - clock
    metadata = json.loads((out / "metadata.json").read_text())
    return {"wall": wall, "analysis": metadata["timings_s"]["analysis"],
            "formulation": metadata["result"].get("formulation")}


SWEEP = """
import sys, time, casmech
clock = time.perf_counter()
table = casmech.sweep(sys.argv[1], grid={{sys.argv[2]: sys.argv[3]}}, workers=0,
                      mode="compiled")
print(time.perf_counter() - clock, (table.status == "complete").sum(), table.wall_s.median())
"""


def sweep(env: dict, path: Path, name: str, grid: str) -> tuple[float, int, float]:
    out = subprocess.run([sys.executable, "-c", SWEEP.format(), str(path), name, grid],
                         env=env, check=True, capture_output=True, text=True)
    total, complete, median = out.stdout.split()
    return float(total), int(complete), float(median)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--before", default="/work/main/src")
    parser.add_argument("--after", default=str(ROOT / "src"))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--samples", type=int, default=20)
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="jointparam_"))
    trees = {"before": args.before, "after": args.after}
    envs = {k: environment(v, work / f"cache_{k}") for k, v in trees.items()}
    for model, (text, name) in MODELS.items():
        path = work / f"{model}.yaml"
        path.write_text(text)
        base = 2.0 if model == "four_bar" else 1.0
        for k, env in envs.items():  # the build, not timed
            run(env, path, name, base, work / f"warm_{k}")
        times = {k: [] for k in trees}
        for r in range(args.repeats):
            for k, env in envs.items():
                times[k].append(run(env, path, name, base + 0.01 * (r + 1), work / f"{k}{r}"))
        for k in trees:
            rows = times[k]
            print(f"{model:16s} {k:6s} formulation {rows[0]['formulation']:6s} "
                  f"wall {statistics.median(r['wall'] for r in rows):.3f} s  "
                  f"analysis {1e3 * statistics.median(r['analysis'] for r in rows):.1f} ms")
        grid = f"{base}:{base * 1.1}:{args.samples}"
        for k, env in envs.items():
            total, complete, median = sweep(env, path, name, grid)
            print(f"{model:16s} {k:6s} sweep of {args.samples}: {total:.2f} s total, "
                  f"{complete} complete, run median {1e3 * median:.1f} ms")


if __name__ == "__main__":
    main()
