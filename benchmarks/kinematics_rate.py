"""Output rows per second of kinematics / inverse dynamics (issue 21: >= 100k rows/s on the
four-bar), side by side in one process:

    python benchmarks/kinematics_rate.py                       # four_bar, me751_pendulum
    python benchmarks/kinematics_rate.py --models four_bar --rows 201 10001 --repeats 5

For each model, mode (interpreted SX bundle, compiled library) and grid length:
- `analyze`: casmech.analyze over the grid (assembly, the E501 check, building the mapped step,
  the rows; not the results table);
- `grid`: the mapped prescribed step alone over the grid (what grows with the rows);
- `per-row`: the loop kinematics ran before the mapped step (kinematics.state_at per row:
  Newton, velocities, accelerations, multipliers by numpy.linalg.lstsq), on the shortest grid;
- `grid, C -O1`: the same step compiled to C by CasADi's JIT (compile time not counted): what a
  compiled library carrying `prescribed_step` would give.
Reported: medians over --repeats of wall and CPU time (process_time: less sensitive to other
processes on a shared machine), as rows per second.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import time
from datetime import datetime, timezone
from functools import partial
from pathlib import Path

import casadi as ca
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import casmech  # noqa: E402
from casmech.formulations import prescribed  # noqa: E402
from casmech.runtime import assembly  # noqa: E402
from casmech.runtime.kinematics import output_times, state_at  # noqa: E402


def timed(run, repeats: int) -> tuple[float, float]:
    """Median wall and CPU seconds of run() over `repeats` calls (after one warm-up)."""
    run()
    walls, cpus = [], []
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.process_time()
        run()
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    return statistics.median(walls), statistics.median(cpus)


def per_row(functions, t_end, step):
    q = assembly.assemble_positions(functions)
    q_dot, q_ddot, previous = np.zeros_like(q), np.zeros_like(q), 0.0
    for t in output_times(0.0, t_end, step):
        h = t - previous
        q, q_dot, q_ddot, _ = state_at(functions, t, q + h * q_dot + 0.5 * h * h * q_ddot,
                                       q_dot + h * q_ddot)
        previous = t


def grid_runner(functions, step_function, t_end, step):
    times = output_times(0.0, t_end, step)
    mapped, padded = prescribed.grid(step_function, len(times))
    times = np.concatenate([times, np.full(padded - len(times), times[-1])])
    u = np.vstack([times, np.diff(times, prepend=0.0)])
    n = functions.n_coordinates
    s0 = np.concatenate([assembly.assemble_positions(functions), np.zeros(2 * n)])
    return lambda: mapped(s0, u)


def jit(step_function: ca.Function) -> ca.Function:
    s, u = (ca.SX.sym(name, step_function.sparsity_in(k)) for k, name in enumerate("su"))
    return ca.Function("prescribed_step_c", [s, u], step_function(s, u),
                       {"jit": True, "compiler": "shell", "jit_options": {"flags": ["-O1"]}})


def measure(model: str, rows: list[int], repeats: int, with_jit: bool) -> list[tuple]:
    lines = []
    loaded = casmech.load(ROOT / "models" / f"{model}.yaml")
    step = loaded.analysis.output_step
    for mode in ("interpreted", "compiled"):
        functions = casmech.compile(loaded, mode)
        analysis = "kinematics" if loaded.analysis.type == "kinematics" else "inverse_dynamics"
        for count in rows:
            t_end = step * (count - 1)
            wall, cpu = timed(partial(casmech.analyze, functions, analysis, t_end=t_end,
                                      output_step=step), repeats)
            lines.append((model, mode, "analyze", count, wall, cpu))
            runner = grid_runner(functions, prescribed.step(functions.functions), t_end, step)
            wall, cpu = timed(runner, repeats)
            lines.append((model, mode, "grid", count, wall, cpu))
            if count == min(rows):
                wall, cpu = timed(partial(per_row, functions, t_end, step),
                                  max(1, repeats // 2))
                lines.append((model, mode, "per-row", count, wall, cpu))
        if with_jit and mode == "interpreted":
            compiled_step = jit(prescribed.step(functions.functions))
            for count in rows:
                runner = grid_runner(functions, compiled_step, step * (count - 1), step)
                wall, cpu = timed(runner, repeats)
                lines.append((model, mode, "grid, C -O1", count, wall, cpu))
    return lines


def header() -> str:
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "src"],
                           capture_output=True, text=True).stdout.strip()
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    return (f"{datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC, commit {commit}"
            f"{' + uncommitted src' if dirty else ''}, {platform.node()} "
            f"({platform.processor() or platform.machine()}), load {load}, "
            f"casadi {ca.__version__}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="+", default=["four_bar", "me751_pendulum"])
    parser.add_argument("--rows", nargs="+", type=int, default=[201, 1001, 10001])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-jit", action="store_true", help="skip the JIT-compiled step")
    args = parser.parse_args()
    print(header(), f"medians of {args.repeats}\n")
    print("| model | mode | what | rows | wall s | CPU s | rows/s (wall) | rows/s (CPU) |")
    print("|---|---|---|---:|---:|---:|---:|---:|")
    for model in args.models:
        for name, mode, what, count, wall, cpu in measure(model, args.rows, args.repeats,
                                                           not args.no_jit):
            print(f"| {name} | {mode} | {what} | {count} | {wall:.4f} | {cpu:.4f} | "
                  f"{count / wall:,.0f} | {count / max(cpu, 1e-9):,.0f} |", flush=True)


if __name__ == "__main__":
    main()
