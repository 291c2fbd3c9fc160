"""A model's first runs on an empty cache, with and without the background build of its library
(issue 36, docs/decisions/mode-auto.md), as whole processes, printed as Markdown with machine,
date and commit.

    python benchmarks/first_runs.py                                   # every system, 3 repeats
    python benchmarks/first_runs.py --systems chain8 four_bar --repeats 5

For each system, in round-robin over the repeats (so the machine's load hits all alike):
  - "first, no build": `casmech run` on an empty cache with $CASMECH_BACKGROUND_BUILD=0;
  - "first, building": the same with the background build on (the default), which leaves a niced
    compiler running for the next run; then "ready after": seconds from that process's exit until
    the cache holds the library and no background build is under way (polled), and "second":
    the next `casmech run`, which loads it;
  - the same three for the API's default call in a process of its own
    (`casmech.analyze(casmech.compile(casmech.load(path)), t_end=...)`).
Wall and CPU (user + sys of the process itself; the detached build is not its child) medians.
The systems: chains from benchmarks/systems.py, gallery models, robots from example-robot-data
imported as benchmarks/robots.py does (skipped without it).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

from process_race import timed  # noqa: E402
from scaling import header as machine  # noqa: E402

CLI = "import sys; from casmech.cli import main; sys.exit(main())"
API = ("import sys, casmech; casmech.analyze(casmech.compile(casmech.load(sys.argv[1])), "
       "t_end=float(sys.argv[2]))")
READY = """
import sys, casmech
from pathlib import Path
from casmech.backends import background, codegen
root = Path(sys.argv[2])
building = [p.name[:-len(background.BUILDING)] for p in root.glob("*" + background.BUILDING)]
busy = any(background.running(key, root) for key in building)
sys.exit(0 if codegen.is_cached(casmech.load(sys.argv[1]), root=root) and not busy else 1)
"""
GALLERY = {"four_bar": "four_bar.yaml", "double_pendulum": "double_pendulum.yaml",
           "slider_crank": "slider_crank.yaml"}
ROBOTS = ("ur5", "talos_arm")


def model_file(name: str, work: Path) -> Path:
    if name in GALLERY:
        return ROOT / "models" / GALLERY[name]
    if name in ROBOTS:
        import numpy as np
        from robots import Robot

        folder = work / name
        folder.mkdir(exist_ok=True)
        robot = Robot(name, folder)
        q0, v0 = robot.draw_state(np.random.default_rng(0))
        return robot.write_casmech(q0, v0, stops=False)
    from casmech_model import yaml_text
    from systems import make

    path = work / f"{name}.yaml"
    path.write_text(yaml_text(make(name)))
    return path


def ready_after(model: Path, cache: Path, env: dict, limit: float = 600.0) -> float:
    """Seconds until the cache holds the model's library (polled every 0.25 s)."""
    start = time.perf_counter()
    while time.perf_counter() - start < limit:
        done = subprocess.run([sys.executable, "-c", READY, str(model), str(cache)], env=env,
                              capture_output=True)
        if done.returncode == 0:
            return time.perf_counter() - start
        time.sleep(0.25)
    return float("nan")


def one_round(model: Path, t_end: float, work: Path, base: dict, tag: str,
              kinds: list[str]) -> dict:
    samples = {}
    for kind, script in (("cli", CLI), ("api", API)):
        if kind not in kinds:
            continue
        args = (["run", str(model), "--t-end", str(t_end), "--out", str(work / "out"),
                 "--quiet"] if kind == "cli" else [str(model), str(t_end)])
        command = [sys.executable, "-c", script, *args]
        cold = work / f"{tag}-{kind}-off"
        samples[f"{kind} first, no build"] = timed(
            command, {**base, "CASMECH_CACHE_DIR": str(cold), "CASMECH_BACKGROUND_BUILD": "0"})
        cache = work / f"{tag}-{kind}-on"
        env = {**base, "CASMECH_CACHE_DIR": str(cache), "CASMECH_BACKGROUND_BUILD": "1"}
        samples[f"{kind} first, building"] = timed(command, env)
        samples[f"{kind} ready after"] = (ready_after(model, cache, env), float("nan"))
        samples[f"{kind} second"] = timed(command, env)
    return samples


def header(args) -> str:
    return f"{machine()}; t_end {args.t_end:g} s; medians of {args.repeats}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--systems", nargs="+",
                        default=["chain8", "chain32", "four_bar", "double_pendulum", *ROBOTS])
    parser.add_argument("--t-end", type=float, default=1.0)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--kinds", nargs="+", default=["cli", "api"], choices=["cli", "api"],
                        help="the command line's run, the API's default call, or both")
    args = parser.parse_args()
    print(header(args), flush=True)
    base = {k: v for k, v in os.environ.items()
            if k not in ("CASMECH_CACHE_DIR", "CASMECH_BACKGROUND_BUILD")}
    base.setdefault("OPENBLAS_NUM_THREADS", "1")
    if any(name in ROBOTS for name in args.systems):  # the imports name the package's meshes
        from robots import robots_folder

        base["CASMECH_ALLOWED_DIRS"] = str(robots_folder().parent)
    results: dict[str, dict[str, list]] = {}
    with tempfile.TemporaryDirectory(prefix="first-runs-") as folder:
        work = Path(folder)
        models = {name: model_file(name, work) for name in args.systems}
        for run in range(args.repeats):
            for name, model in models.items():
                for label, sample in one_round(model, args.t_end, work, base,
                                               f"{name}-{run}", args.kinds).items():
                    results.setdefault(name, {}).setdefault(label, []).append(sample)
                print(f"  round {run + 1}: {name} done", file=sys.stderr, flush=True)
    labels = list(next(iter(results.values())))
    print("\n| system | " + " | ".join(labels) + " |")
    print("|---|" + "---:|" * len(labels))
    for name, rows in results.items():
        cells = []
        for label in labels:
            wall = statistics.median(s[0] for s in rows[label])
            cpu = [s[1] for s in rows[label] if s[1] == s[1]]
            cells.append(f"{wall:.2f}" + (f" ({statistics.median(cpu):.2f})" if cpu else ""))
        print(f"| {name} | " + " | ".join(cells) + " |")
    print("\nwall s (CPU s of the process itself)")


if __name__ == "__main__":
    main()
