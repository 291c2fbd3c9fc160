"""What a user waits for: `casmech run chainN.yaml --t-end T` against a Python process stepping
MuJoCo's RK4, both as whole processes, in one run (issue 36), printed as Markdown with machine,
date and commit.

    python benchmarks/process_race.py                         # chain8 and chain32, 10 s, 7 repeats
    python benchmarks/process_race.py --systems chain8 --t-end 1 --repeats 5
    python benchmarks/process_race.py --src /work/main/src --src src    # before/after, one run
    python benchmarks/process_race.py --commit a5d48e1 --commit HEAD    # src/ at two commits

The models come from benchmarks/systems.py (casmech_model.yaml_text, mujoco_model.mjcf), written
to a temporary folder. casmech: the console script (`from casmech.cli import main`) with
PYTHONPATH=<src>, default flags but --t-end, results written to a temporary folder; "warm
cache" means CASMECH_CACHE_DIR holds the model's compiled library (built once before timing by
`casmech run --mode compiled`), "empty cache" a fresh cache folder per run. MuJoCo: `python -c`
importing mujoco and NumPy, reading the MJCF, stepping RK4 at --mujoco-dt and recording qpos
every 0.01 s (as the benchmark's MuJoCo runner does). Commands run round-robin, so a change in
the machine's load hits all alike; medians of wall and CPU (user + sys of the child) after one
untimed warm-up of each. After each command the next waits, untimed, until the background
build an empty-cache run started (and its compilers) has ended (`settle`), so that no command
is timed beside another's build.
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from casmech_model import yaml_text  # noqa: E402
from mujoco_model import mjcf  # noqa: E402
from run import export_src  # noqa: E402
from systems import OUTPUT_STEP, make  # noqa: E402

CONSOLE = "import sys; from casmech.cli import main; sys.exit(main())"
MUJOCO = """
import sys, numpy as np, mujoco
model = mujoco.MjModel.from_xml_path(sys.argv[1]); data = mujoco.MjData(model)
t_end, every = float(sys.argv[2]), int(round(float(sys.argv[3]) / model.opt.timestep))
qpos = np.empty((int(round(t_end / float(sys.argv[3]))) + 1, model.nq)); qpos[0] = data.qpos
for k in range(1, len(qpos)):
    mujoco.mj_step(model, data, nstep=every); qpos[k] = data.qpos
"""


def timed(command: list[str], env: dict) -> tuple[float, float]:
    """(wall, CPU user + sys) of one process [s]."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=900)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def cases(systems: list[str], sources: list[Path], work: Path, t_end: float, dt: float):
    """(system, label, command, environment maker(run) -> env)."""
    # bytecode written to a private folder by the untimed first run of each command, as
    # `pip install` byte-compiles (an inherited PYTHONDONTWRITEBYTECODE would make every
    # process compile casmech's sources again)
    base = {k: v for k, v in os.environ.items()
            if k not in ("PYTHONPATH", "PYTHONDONTWRITEBYTECODE")}
    base.update(PYTHONPYCACHEPREFIX=str(work / "pycache"), OPENBLAS_NUM_THREADS="1")
    rows = []
    for name in systems:
        system = make(name)
        model = work / f"{name}.yaml"
        model.write_text(yaml_text(system))
        xml = work / f"{name}_mujoco.xml"
        xml.write_text(mjcf(system, dt))
        rows.append((name, f"MuJoCo RK4 dt {dt:g}, {name}",
                     [sys.executable, "-c", MUJOCO, str(xml), str(t_end), str(OUTPUT_STEP)],
                     lambda run: base))
        for k, src in enumerate(sources):
            run_cmd = [sys.executable, "-c", CONSOLE, "run", str(model), "--t-end", str(t_end),
                       "--out", str(work / "out"), *quiet(src, base)]
            warm = {**base, "PYTHONPATH": str(src), "CASMECH_CACHE_DIR": str(work / f"warm{k}")}
            rows.append((name, f"casmech run {name} (warm cache) [{k}]", run_cmd,
                         lambda run, warm=warm: warm))
            rows.append((name, f"casmech run {name} (empty cache) [{k}]", run_cmd,
                         lambda run, src=src, k=k: {**base, "PYTHONPATH": str(src),
                                                    "CASMECH_CACHE_DIR":
                                                    str(work / f"cold{k}-{run}")}))
            build = [*run_cmd, "--mode", "compiled"]
            timed(build, warm)  # the warm cache's library, not timed
    return rows


def settle(cache: str | None, limit: float = 900.0) -> None:
    """Waits (untimed) until no process works for `cache` any more: an empty-cache run's
    background build (a detached child and its compilers, CASMECH_CACHE_DIR=`cache` in their
    environment) goes on after the run, and would load the machine under the commands timed
    next. Linux (/proc); elsewhere, and for the warm rows, which start none, it returns."""
    if cache is None or not Path("/proc").is_dir():
        return
    marker = f"CASMECH_CACHE_DIR={cache}".encode()
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        busy = False
        for entry in Path("/proc").iterdir():
            if not entry.name.isdigit() or int(entry.name) == os.getpid():
                continue
            try:
                environ = (entry / "environ").read_bytes()
            except OSError:  # gone, or not ours
                continue
            if marker in environ.split(b"\0"):
                busy = True
                break
        if not busy:
            return
        time.sleep(0.05)


def quiet(src: Path, base: dict) -> list[str]:
    """["--quiet"] where that source's `casmech run` has the flag (older commits do not)."""
    usage = subprocess.run([sys.executable, "-c", CONSOLE, "run", "--help"], capture_output=True,
                           text=True, env={**base, "PYTHONPATH": str(src)}).stdout
    return ["--quiet"] if "--quiet" in usage else []


def describe(src: Path, commits: dict[Path, str]) -> str:
    if src in commits:  # exported by --commit
        return commits[src]

    def git(*args):
        return subprocess.run(["git", "-C", str(src), *args], capture_output=True,
                              text=True).stdout.strip()
    dirty = git("status", "--porcelain", "--", str(src))
    return f"{git('rev-parse', '--short', 'HEAD') or '?'}{'+' if dirty else ''}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--systems", nargs="+", default=["chain8", "chain32"])
    parser.add_argument("--src", action="append", type=Path,
                        help="casmech source tree(s), side by side (default: ../src)")
    parser.add_argument("--commit", action="append", default=[],
                        help="src/ as of this git commit (exported to a temporary folder), "
                             "side by side after the --src trees")
    parser.add_argument("--t-end", type=float, default=10.0)
    parser.add_argument("--mujoco-dt", type=float, default=1e-3)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    sources = [path.resolve() for path in (args.src or ([] if args.commit
                                                         else [HERE.parent / "src"]))]
    commits = {}
    for commit in args.commit:
        full, src = export_src(commit)
        commits[src] = full[:10]
        sources.append(src)
    samples: dict[str, list] = {}
    # (an empty-cache run's background build may still be writing there at the end)
    with tempfile.TemporaryDirectory(prefix="process-race-", ignore_cleanup_errors=True) as folder:
        rows = cases(args.systems, sources, Path(folder), args.t_end, args.mujoco_dt)
        for run in range(args.repeats + 1):  # run 0: warm-up
            for system, label, command, env in rows:
                environment = env(run)
                sample = timed(command, environment)
                if run:
                    samples.setdefault((system, label), []).append(sample)
                settle(environment.get("CASMECH_CACHE_DIR"))
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, load {load} "
          f"at the end; Python {platform.python_version()}; "
          f"{datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC; --t-end {args.t_end:g}; sources: "
          + ", ".join(f"[{k}] {src} @ {describe(src, commits)}" for k, src in enumerate(sources))
          + f"; medians of {args.repeats} after a warm-up\n")
    print("| process | wall [s] | CPU [s] | wall / MuJoCo | CPU / MuJoCo |")
    print("|---|---:|---:|---:|---:|")
    for name in args.systems:
        mujoco = samples[(name, f"MuJoCo RK4 dt {args.mujoco_dt:g}, {name}")]
        peer = [statistics.median(sample[k] for sample in mujoco) for k in (0, 1)]
        for (system, label), values in samples.items():
            if system == name:
                wall = statistics.median(w for w, _ in values)
                cpu = statistics.median(c for _, c in values)
                print(f"| {label} | {wall:.3f} | {cpu:.3f} | {wall / peer[0]:.2f} | "
                      f"{cpu / peer[1]:.2f} |")


if __name__ == "__main__":
    main()
