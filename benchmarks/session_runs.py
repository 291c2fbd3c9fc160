"""One session's repeated default calls from an empty cache (issue 36, docs/decisions/mode-auto.md):
`functions = casmech.compile(casmech.load(path))`, then `casmech.analyze(functions, "dynamics",
t_end=1, rtol=r, atol=r/100)` over and over in the same process while the library is built
behind, until the calls have run compiled (backends.handover) for a while; MuJoCo's RK4 run of
the same system in the same process, at the settings that reach 1e-7 m at t = 1 s.

    python benchmarks/session_runs.py                                # chain8, four_bar, ur5
    python benchmarks/session_runs.py --systems chain8 --repeats 5 --gap 0.1

Each system and repeat is a process of its own (the script run with --one) on an empty cache
with the background build on, the systems in round-robin over the repeats. Per process: the
first call (load + compile + analyze, as a notebook's first cell), the calls before the handover
(interpreted: median of the repeated ones), the seconds from compile() to the first compiled
call's start, that call (it loads the library and builds the compiled run's integrator), the
calls after it (median), and MuJoCo's run (median of 7): CPU times of the process itself
(the niced build is not its child), wall in brackets. `--gap` sleeps between calls (a person at
a notebook); 0, the default, calls back to back, which shares the cores with the build most.
The settings (casmech rtol, MuJoCo step) are those reaching 1e-7 m in RESULTS.md: run.py's
table for chain8 and the four-bar (benchmarks/systems.py), robots.py's for UR5 (seed 36; needs
`pin` and `example-robot-data`).
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

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from scaling import header as machine  # noqa: E402

T_END = 1.0
# system -> (casmech rtol, MuJoCo RK4 step) reaching 1e-7 m at t = 1 s (module docstring)
SETTINGS = {"chain8": (1e-8, 0.002), "four_bar": (1e-8, 0.001), "ur5": (1e-7, 0.01)}
AFTER = 30  # compiled calls timed after the handover
LIMIT = 300.0  # s: a session that has not handed over by then stops (reported as none)


def _mujoco(name: str, work: Path, step: float):
    """(the model file casmech loads, a callable running MuJoCo 1 s) for `name`."""
    if name == "ur5":
        import mujoco
        import numpy as np
        from robots import Robot, mujoco_run

        robot = Robot(name, work)
        q0, v0 = robot.draw_state(np.random.default_rng(36))
        steps = round(T_END / step)
        model = robot.mujoco_model(steps)
        data = mujoco.MjData(model)
        return robot.write_casmech(q0, v0, stops=False), \
            lambda: mujoco_run(robot, model, data, q0, v0, steps)
    from casmech_model import yaml_text
    from mujoco_model import Runner
    from systems import make

    system = make(name)
    path = work / f"{name}.yaml"
    path.write_text(yaml_text(system))
    runner = Runner(system)
    return path, lambda: runner.run({"timestep": step}, t_end=T_END)


def session(name: str, work: Path, gap: float) -> dict:
    """One process's calls (module docstring), as JSON-able numbers."""
    rtol, step = SETTINGS[name]
    path, mujoco_run = _mujoco(name, work, step)
    mujoco_run()  # its model built
    mujoco = []
    for _ in range(7):
        start = time.process_time()
        mujoco_run()
        mujoco.append(time.process_time() - start)
    import casmech

    calls = []  # (seconds since compile() began, CPU s, wall s, mode)
    begin = time.perf_counter()
    cpu = time.process_time()
    functions = casmech.compile(casmech.load(path))
    compiled = 0
    while compiled < AFTER and time.perf_counter() - begin < LIMIT:
        at, wall, cpu_at = time.perf_counter(), time.perf_counter(), time.process_time()
        result = casmech.analyze(functions, "dynamics", t_end=T_END, rtol=rtol,
                                 atol=rtol / 100)
        mode = result.metadata["mode"]
        if not calls:  # the first call counts load and compile
            at, wall, cpu_at = begin, begin, cpu
        calls.append((at - begin, time.process_time() - cpu_at, time.perf_counter() - wall,
                      mode))
        compiled += mode == "compiled"
        if gap:
            time.sleep(gap)
    before = [c for c in calls[1:] if c[3] == "interpreted"]
    after = [c for c in calls if c[3] == "compiled"]
    return {"first": calls[0][1:3], "before": len(before),
            "before_cpu": statistics.median(c[1] for c in before) if before else None,
            "before_wall": statistics.median(c[2] for c in before) if before else None,
            "handover_at": after[0][0] if after else None,
            "handover_call": after[0][1:3] if after else None,
            "after_cpu": statistics.median(c[1] for c in after[1:]) if len(after) > 1 else None,
            "after_wall": statistics.median(c[2] for c in after[1:]) if len(after) > 1 else None,
            "mujoco_cpu": statistics.median(mujoco), "rtol": rtol, "step": step}


def ms(value) -> str:
    return "-" if value is None else f"{1e3 * value:.2f}"


def ratio(a, b) -> str:
    return "-" if a is None or b is None else f"{a / b:.2f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--systems", nargs="+", default=list(SETTINGS), choices=list(SETTINGS))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--gap", type=float, default=0.0, help="seconds between calls")
    parser.add_argument("--one", help=argparse.SUPPRESS)
    parser.add_argument("--work", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(session(args.one, Path(args.work), args.gap)))
        return
    print(f"{machine()}; t_end {T_END:g} s; gap {args.gap:g} s; medians of {args.repeats}",
          flush=True)
    base = {k: v for k, v in os.environ.items() if k != "CASMECH_CACHE_DIR"}
    base.update(CASMECH_BACKGROUND_BUILD="1", OPENBLAS_NUM_THREADS="1")
    if "ur5" in args.systems:  # the import names the package's meshes
        from robots import robots_folder

        base["CASMECH_ALLOWED_DIRS"] = str(robots_folder().parent)
    runs: dict[str, list[dict]] = {}
    with tempfile.TemporaryDirectory(prefix="session-runs-") as folder:
        for repeat in range(args.repeats):
            for name in args.systems:
                work = Path(folder) / f"{name}-{repeat}"
                work.mkdir()
                env = {**base, "CASMECH_CACHE_DIR": str(work / "cache")}
                done = subprocess.run([sys.executable, __file__, "--one", name, "--work",
                                       str(work), "--gap", str(args.gap)], env=env,
                                      capture_output=True, text=True, timeout=2 * LIMIT)
                if done.returncode != 0:
                    raise SystemExit(f"{name} failed:\n{done.stderr}")
                runs.setdefault(name, []).append(json.loads(done.stdout.splitlines()[-1]))
                print(f"  round {repeat + 1}: {name} done", file=sys.stderr, flush=True)

    def median(rows, key, index=None):
        values = [r[key] if index is None else r[key][index] for r in rows
                  if r[key] is not None]
        return statistics.median(values) if values else None

    print("\n| system | rtol; MuJoCo dt | first call ms | calls before | before ms | handover "
          "after s | handover call ms | after ms | MuJoCo ms | before / MuJoCo | after / "
          "MuJoCo | before / after |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, rows in runs.items():
        before, after = median(rows, "before_cpu"), median(rows, "after_cpu")
        mj = median(rows, "mujoco_cpu")
        handover = median(rows, "handover_at")
        print(f"| {name} | {rows[0]['rtol']:g}; {rows[0]['step']:g} | "
              f"{ms(median(rows, 'first', 0))} ({ms(median(rows, 'first', 1))}) | "
              f"{median(rows, 'before'):.0f} | {ms(before)} ({ms(median(rows, 'before_wall'))}) | "
              f"{'-' if handover is None else f'{handover:.1f}'} | "
              f"{ms(median(rows, 'handover_call', 0))} ({ms(median(rows, 'handover_call', 1))}) | "
              f"{ms(after)} ({ms(median(rows, 'after_wall'))}) | {ms(mj)} | "
              f"{ratio(before, mj)} | {ratio(after, mj)} | {ratio(before, after)} |")
    print("\nCPU ms of the process itself (wall ms); calls before: the interpreted calls after "
          "the first; handover after: s from compile() to the first compiled call")


if __name__ == "__main__":
    main()
