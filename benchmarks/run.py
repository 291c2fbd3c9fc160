"""Benchmark casmech against Exudyn and MuJoCo on the N-link spherical chain and a four-bar.

    python benchmarks/run.py                       # full run (hours: casmech is slow)
    python benchmarks/run.py --quick               # chain2 + four_bar, short sweeps, 1 repeat
    python benchmarks/run.py --systems chain2 chain8 --tools casmech mujoco --repeats 5

For every system and tool the accuracy knob is swept (casmech: rtol with atol = rtol/100; Exudyn:
the step size h of its generalized-alpha solver; MuJoCo: the RK4 time step). Every setting runs
in its own process (worker.py) `--repeats` times (more for short runs); the wall time of the 10 s
simulation (median; --t-end changes the span) and the error at t = 1 s (max distance of the bars'
CMs and tips from the reference) are recorded. The reference is an independent planar
minimal-coordinate solution (reference.py), cross-checked against each tool at its tightest
setting.

Slow settings are bounded: a run is stopped after --timeout seconds; and once some setting of a
tool has reached the tightest accuracy level, a run of that tool that takes longer than
--prune-factor x that setting's median is stopped (it cannot be the fastest way to any level).
After a timeout the tool's remaining settings on that system are skipped. Every such event is
recorded and shown in the tables.

Several --casmech-commit commits make each casmech tool one tool per commit (`casmech@a5d48e1`,
`casmech-c@a5d48e1`, `casmech@8730f06`, ...), each importing src/ as of its commit; the tools run
interleaved (setting k of every tool before setting k + 1 of any), so a change of the machine's
load hits every commit alike, and the tables add each commit's figures against the first's.

Writes benchmarks/results/<date>_<time>.json and .md (tables) and copies them to latest.*.
"""

from __future__ import annotations

import argparse
import atexit
import compileall
import datetime
import io
import json
import os
import platform
import selectors
import shutil
import signal
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

# single-threaded BLAS in this process too (see --threads); must precede the NumPy import
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import numpy as np  # noqa: E402
import systems  # noqa: E402
from casmech_model import TOOLS as CASMECH_TOOLS  # noqa: E402
from casmech_model import yaml_text  # noqa: E402
from mujoco_model import mjcf  # noqa: E402

from reference import Planar  # noqa: E402

HERE = Path(__file__).resolve().parent
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
THREADS = 1  # --threads
LEVELS = (1e-3, 1e-5, 1e-7)  # m, accuracy levels of the summary tables

SWEEPS = {
    # casmech: tight to loose, the order of increasing cost for casmech today (see RESULTS.md)
    "casmech": [{"rtol": r, "atol": r * 1e-2}
                for r in (1e-12, 1e-11, 1e-10, 1e-9, 1e-8, 1e-6, 1e-4)],
    "exudyn": [{"h": h} for h in (1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5)],
    "mujoco": [{"timestep": h} for h in (1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4)],
}
SWEEPS["exudyn-fast"] = SWEEPS["exudyn"]
QUICK_SWEEPS = {
    "casmech": [{"rtol": 1e-12, "atol": 1e-14}, {"rtol": 1e-8, "atol": 1e-10}],
    "exudyn": [{"h": h} for h in (1e-2, 1e-3, 1e-4)],
    "mujoco": [{"timestep": h} for h in (1e-2, 1e-3, 1e-4)],
}
QUICK_SWEEPS["exudyn-fast"] = QUICK_SWEEPS["exudyn"]
# tightest settings, run to t = 1 s only, to cross-check the planar reference
CROSS_CHECK = {"casmech": {"rtol": 1e-12, "atol": 1e-14},
               "casmech-c": {"rtol": 1e-12, "atol": 1e-14}, "exudyn": {"h": 1e-5},
               "exudyn-fast": {"h": 1e-5}, "mujoco": {"timestep": 1e-5}}
KNOB = {"casmech": "rtol", "casmech-c": "rtol", "exudyn": "h", "exudyn-fast": "h",
        "mujoco": "timestep"}
for _tool in (*CASMECH_TOOLS, "casadi-script"):  # rtol sweeps and cross-checks as casmech
    for _table in (SWEEPS, QUICK_SWEEPS, CROSS_CHECK, KNOB):
        _table[_tool] = _table["casmech"]


# --casmech-commit with several commits: commit label -> the exported src/ folder; a tool
# "casmech-c@<label>" is casmech-c importing casmech from that folder
SNAPSHOTS: dict[str, Path] = {}


def base(tool: str) -> str:
    """The tool without its commit: "casmech-c@a5d48e1" -> "casmech-c"."""
    return tool.partition("@")[0]


def knob(tool: str, setting: dict) -> str:
    return f"{KNOB[base(tool)]}={setting[KNOB[base(tool)]]:g}"


def call_worker(tool: str, system: str, setting: dict, repeats: int, t_end: float,
                deadline: float, stop_after=None) -> dict:
    """Run worker.py; `deadline`: seconds a single run may take (the first one with the model
    build); `stop_after()`: a tighter limit per run (re-read while waiting; None: none)."""
    env = dict(os.environ)
    if THREADS:
        env.update({name: str(THREADS) for name in THREAD_VARIABLES})
    if tool == "exudyn-fast":
        env["EXUDYN_MODULE"] = "fast"
    label = tool.partition("@")[2]
    if label:  # this commit's src/ first on the path
        env["PYTHONPATH"] = os.pathsep.join(
            p for p in (str(SNAPSHOTS[label]), os.environ.get("PYTHONPATH")) if p)
    if CASMECH_TOOLS.get(base(tool), {}).get("mode") == "compiled":
        # simulation-speed flags; a private cache so the build is timed
        env["CASMECH_CFLAGS"] = "-O2"
        env["CASMECH_CACHE_DIR"] = tempfile.mkdtemp(prefix="casmech_bench_cache_")
    command = [sys.executable, str(HERE / "worker.py"), base(tool), system, json.dumps(setting),
               "--repeats", str(repeats), "--t-end", repr(t_end)]
    with tempfile.TemporaryFile("w+") as stderr:
        process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=stderr, env=env,
                                   text=True, start_new_session=True)
        try:
            outcome = _follow(process, tool, system, setting, deadline, stop_after)
        finally:  # also on Ctrl-C / SIGTERM: never leave a worker behind
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()
        if process.returncode not in (0, -signal.SIGKILL) and outcome["status"] == "ok":
            stderr.seek(0)
            outcome.update(status="error", message=f"worker exit {process.returncode}",
                           stderr=stderr.read()[-4000:])
    if "CASMECH_CACHE_DIR" in env and env["CASMECH_CACHE_DIR"] != os.environ.get(
            "CASMECH_CACHE_DIR"):  # the worker's private cache
        shutil.rmtree(env["CASMECH_CACHE_DIR"], ignore_errors=True)
    return outcome


def _follow(process, tool, system, setting, deadline, stop_after) -> dict:
    selector = selectors.DefaultSelector()
    selector.register(process.stdout, selectors.EVENT_READ)
    outcome = {"tool": tool, "system": system, "setting": setting, "runs": [], "status": "ok"}
    last = time.perf_counter()
    while True:
        now = time.perf_counter()
        whole = deadline - (now - last)  # every run (the first with the build) gets `deadline`
        # pruning bounds the timed runs only: the model's build is bounded by `deadline`
        single = stop_after() if stop_after and "build" in outcome else None
        this_run = single - (now - last) if single is not None else float("inf")
        if min(whole, this_run) <= 0:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
            if this_run <= 0:  # pruned: slower than a setting that reaches every level
                outcome.update(status="stopped", limit=single, seconds=now - last)
            else:
                outcome.update(status="timeout", limit=deadline, seconds=now - last)
            break
        if not selector.select(timeout=min(whole, this_run, 5.0)):
            continue
        chunk = process.stdout.readline()
        if not chunk:
            process.wait()
            break
        line = chunk.strip()
        if not line.startswith("{"):  # a tool's own console output
            if line:
                outcome.setdefault("console", []).append(line)
            continue
        event = json.loads(line)
        if event["event"] == "build":
            outcome["build"] = event
            last = time.perf_counter()
        elif event["event"] == "warmup":
            outcome["warmup"] = event["wall"]
            last = time.perf_counter()
        elif event["event"] == "run":
            outcome["runs"].append(event)
            last = time.perf_counter()
        elif event["event"] == "error":
            outcome.update(status="error", message=event["message"],
                           traceback=event["traceback"])
    return outcome


def summarize(outcome: dict, reference: np.ndarray) -> dict:
    runs = outcome.pop("runs")
    walls = [r["wall"] for r in runs]
    errors = [systems.error(r["points"], reference) for r in runs]
    outcome["walls"] = walls
    cpus = [r["cpu"] for r in runs if r.get("cpu") is not None]
    if cpus:  # the process's CPU time of the same span: steadier than wall on a loaded machine
        outcome["cpus"] = cpus
        outcome["cpu_median"] = statistics.median(cpus)
    if walls:
        outcome["median"] = statistics.median(walls)
        outcome["error"] = max(errors)  # deterministic: the repeats agree
        outcome["error_spread"] = max(errors) - min(errors)
        outcome["extra"] = runs[-1].get("extra", {})
        outcome["points"] = runs[-1]["points"]  # at T_CHECK, to re-evaluate errors later
    return outcome


def best_at(results: list[dict], tool: str, level: float):
    """The fastest setting of `tool` whose error at t = 1 s is within `level`."""
    ok = [r for r in results if r["tool"] == tool and "median" in r and r["error"] <= level]
    return min(ok, key=lambda r: r["median"]) if ok else None


def run_system(name: str, tools: list[str], args, sweeps: dict, log) -> dict:
    system = systems.make(name)
    log(f"== {name}: {system.description}")
    start = time.perf_counter()
    planar = Planar(system)
    ref = planar.solve()
    entry = {"system": name, "description": system.description, "bars": len(system.bars),
             "reference": {"method": "planar minimal coordinates, RK4 with step halving "
                                     "(reference.py)",
                           "seconds": time.perf_counter() - start, "step": ref["step"],
                           "agreement": ref["agreement"], "evaluations": ref["evaluations"],
                           "loop_residual": ref["constraint"],
                           "points": ref["points"].tolist()},
             "cross_check": [], "results": []}
    log(f"   reference: {entry['reference']['seconds']:.2f} s, RK4 h = {ref['step']:g} s, "
        f"last halving changed the points by {ref['agreement']:.1e} m")
    reference = ref["points"]
    if not args.no_cross_check:
        for tool in tools:
            setting = CROSS_CHECK[base(tool)]
            outcome = call_worker(tool, name, setting, 1, systems.T_CHECK, args.timeout)
            outcome = summarize(outcome, reference)
            entry["cross_check"].append(outcome)
            log(f"   cross-check {tool} {knob(tool, setting)} (to t = 1 s): "
                + (f"{outcome['error']:.2e} m from the reference" if "error" in outcome
                   else outcome["status"]))
    # every tool's sweep, interleaved: setting k of each tool, then setting k + 1 of each
    mine: dict[str, list[dict]] = {tool: [] for tool in tools}
    skip_reason: dict[str, str | None] = {tool: None for tool in tools}
    for tool in tools:
        if (tool.startswith("casmech") and args.casmech_max_bars
                and len(system.bars) > args.casmech_max_bars):
            skip_reason[tool] = f"--casmech-max-bars {args.casmech_max_bars}"
            log(f"   {tool}: skipped (more than {args.casmech_max_bars} bars)")
    for k in range(max(len(sweeps[base(tool)]) for tool in tools)):
        for tool in tools:
            if k >= len(sweeps[base(tool)]):
                continue
            setting = sweeps[base(tool)][k]
            if skip_reason[tool]:
                mine[tool].append({"tool": tool, "system": name, "setting": setting,
                                   "status": "skipped", "message": skip_reason[tool]})
                continue

            def stop_after(tool=tool):
                best = best_at(mine[tool], tool, LEVELS[-1])
                return max(args.prune_floor, args.prune_factor * best["median"]) if best else None

            outcome = summarize(call_worker(tool, name, setting, args.repeats,
                                            args.t_end, args.timeout, stop_after), reference)
            mine[tool].append(outcome)
            if "median" in outcome:
                log(f"   {tool:18s} {knob(tool, setting):16s} {outcome['median']:10.4f} s "
                    f"(n={len(outcome['walls'])})  error {outcome['error']:.2e} m"
                    + ("" if outcome["status"] == "ok" else f"  [{outcome['status']}]"))
            else:
                log(f"   {tool:18s} {knob(tool, setting):16s} {outcome['status']}: "
                    f"{outcome.get('message', '')} after {outcome.get('seconds', 0):.0f} s")
            if outcome["status"] == "timeout":
                skip_reason[tool] = (f"an earlier setting timed out (--timeout {args.timeout:g} s)")
            elif outcome["status"] == "error" and KNOB[base(tool)] != "rtol":
                skip_reason[tool] = "an earlier setting failed"  # an rtol sweep goes on: a
                # failure at the tightest rtol says nothing of the looser ones
            elif (not tool.startswith("casmech") and "median" in outcome
                  and outcome["error"] <= LEVELS[-1]
                  and outcome["median"] > args.skip_after):
                skip_reason[tool] = (f"a cheaper setting already reached {LEVELS[-1]:g} m and "
                                     f"took more than {args.skip_after:g} s")
    for tool in tools:
        entry["results"] += mine[tool]
    return entry


def machine() -> dict:
    info = {"date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
            "python": platform.python_version(), "platform": platform.platform()}
    try:
        lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        for line in lscpu.splitlines():
            key, _, value = line.partition(":")
            if key.strip() in ("Model name", "CPU(s)", "Thread(s) per core", "Hypervisor vendor"):
                info[key.strip()] = value.strip()
    except OSError:
        pass
    for module in ("numpy", "scipy", "casadi", "exudyn", "mujoco"):
        try:
            info[module] = __import__(module).__version__
        except Exception as error:  # noqa: BLE001 - reported, not fatal
            info[module] = f"unavailable ({error})"
    try:
        repo = HERE.parent
        info["git_commit"] = subprocess.run(["git", "rev-parse", "HEAD"], cwd=repo,
                                            capture_output=True, text=True).stdout.strip()
        status = subprocess.run(["git", "status", "--porcelain", "src"], cwd=repo,
                                capture_output=True, text=True).stdout.strip()
        info["src_dirty"] = bool(status)
    except OSError:
        pass
    probe = subprocess.run([sys.executable, "-c", "import casmech; print(casmech.__file__)"],
                           capture_output=True, text=True)
    info["casmech_file"] = ("each tool's commit's exported src/" if SNAPSHOTS
                            else probe.stdout.strip() or probe.stderr.strip()[-300:])
    snapshot = os.environ.get("CASMECH_BENCH_COMMIT")
    if SNAPSHOTS:
        info["casmech_source"] = ("src/ of each tool's commit (--casmech-commit): " + ", ".join(
            f"@{label} = {folder.parent.name.split('_')[1]}"
            for label, folder in SNAPSHOTS.items()))
        info["commits"] = list(SNAPSHOTS)
    else:
        info["casmech_source"] = (f"src/ of git commit {snapshot} (--casmech-commit)" if snapshot
                                  else "the installed casmech (git HEAD above; src_dirty: "
                                       "uncommitted changes in src/)")
    info["loadavg_start"] = os.getloadavg()
    return info


def export_src(commit: str) -> tuple[str, Path]:
    """src/ as of `commit` in a temporary folder (removed at exit), compiled to bytecode as
    `pip install` leaves an installed casmech (else, where PYTHONDONTWRITEBYTECODE is set,
    every worker compiles every module it imports, and a commit with more modules looks
    slower to start): (full hash, its src/)."""
    repo = HERE.parent
    full = subprocess.run(["git", "rev-parse", "--verify", f"{commit}^{{commit}}"], cwd=repo,
                          capture_output=True, text=True, check=True).stdout.strip()
    folder = Path(tempfile.mkdtemp(prefix=f"casmech_{full[:10]}_"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    archive = subprocess.run(["git", "archive", "--format=tar", full, "src"], cwd=repo,
                             capture_output=True, check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(folder, filter="data")
    compileall.compile_dir(folder / "src", quiet=1)
    return full, folder / "src"


def use_snapshot(commit: str) -> None:
    """Export src/ at `commit` and make the workers import casmech from there."""
    full, src = export_src(commit)
    os.environ["PYTHONPATH"] = os.pathsep.join(
        p for p in (str(src), os.environ.get("PYTHONPATH")) if p)
    os.environ["CASMECH_BENCH_COMMIT"] = full


def use_snapshots(commits: list[str], tools: list[str]) -> list[str]:
    """Export src/ at each commit; every casmech tool becomes one tool per commit, labelled by
    the commit's short hash, the commits of a tool side by side."""
    for commit in commits:
        full, src = export_src(commit)
        SNAPSHOTS[full[:7]] = src
    if len(SNAPSHOTS) < len(commits):
        raise SystemExit("--casmech-commit: two of the commits are the same commit")
    return [f"{tool}@{label}" if tool in CASMECH_TOOLS else tool
            for tool in tools for label in (SNAPSHOTS if tool in CASMECH_TOOLS else [None])]


def export_models() -> None:
    """The generated casmech YAML (and MuJoCo MJCF) for people to look at."""
    folder = HERE / "models"
    folder.mkdir(exist_ok=True)
    for name in ("chain2", "four_bar"):
        system = systems.make(name)
        (folder / f"{name}.yaml").write_text(yaml_text(system))
        (folder / f"{name}_mujoco.xml").write_text(mjcf(system, 1e-3))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="\n".join(__doc__.splitlines()[1:]))
    parser.add_argument("--systems", nargs="+",
                        default=["chain2", "four_bar", "chain8", "chain32", "chain128"],
                        help="chain<N> and/or four_bar")
    parser.add_argument("--tools", nargs="+",
                        default=["casmech", "casmech-c", "exudyn", "mujoco"],
                        choices=[*CASMECH_TOOLS, "casadi-script", "exudyn", "exudyn-fast",
                                 "mujoco"])
    parser.add_argument("--repeats", type=int, default=3,
                        help="timed runs per setting (at least 7 for runs under 1 s)")
    parser.add_argument("--quick", action="store_true",
                        help="chain2 and four_bar, short sweeps, 1 repeat, no cross-check")
    parser.add_argument("--timeout", type=float, default=1800.0,
                        help="seconds a single run may take (the first with the model build)")
    parser.add_argument("--prune-factor", type=float, default=1.5)
    parser.add_argument("--prune-floor", type=float, default=60.0,
                        help="never stop a run by pruning before this many seconds")
    parser.add_argument("--skip-after", type=float, default=5.0,
                        help="Exudyn/MuJoCo: stop refining once a setting reached the tightest "
                             "level and took longer than this (s)")
    parser.add_argument("--casmech-max-bars", type=int, default=0,
                        help="skip casmech on systems with more bars (0: no limit)")
    parser.add_argument("--no-cross-check", action="store_true")
    parser.add_argument("--t-end", type=float, default=systems.T_END,
                        help="simulated time of every timed run (default %(default)g s; the "
                        "error is measured at 1 s either way, so --t-end 1 times only the span "
                        "whose accuracy is measured)")
    parser.add_argument("--threads", type=int, default=1,
                        help="BLAS/OpenMP threads of the workers (OPENBLAS_NUM_THREADS etc.); "
                             "0: leave the environment alone. Default 1: every tool runs "
                             "single-threaded (casmech's NumPy calls were 10-60x slower with "
                             "2 OpenBLAS threads on the 2-core benchmark machine)")
    parser.add_argument("--casmech-commit", metavar="COMMIT", nargs="+",
                        help="benchmark casmech's src/ as of this git commit (exported to a "
                             "temporary directory and put first on PYTHONPATH) instead of the "
                             "installed casmech; several commits: each casmech tool once per "
                             "commit (casmech@<hash>, ...), interleaved, with tables of each "
                             "commit against the first")
    parser.add_argument("--casmech-rtols", type=float, nargs="+", metavar="RTOL",
                        help="casmech's rtol sweep (atol = rtol / 100) instead of the default")
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args(argv)
    global THREADS
    THREADS = args.threads
    signal.signal(signal.SIGTERM, lambda *_: sys.exit("terminated"))
    sweeps = SWEEPS
    if args.quick:
        if args.systems == parser.get_default("systems"):
            args.systems = ["chain2", "four_bar"]
        args.repeats = 1
        args.no_cross_check = True
        sweeps = QUICK_SWEEPS
    if args.casmech_rtols:
        mine = [{"rtol": r, "atol": r * 1e-2} for r in sorted(args.casmech_rtols)]
        sweeps = {**sweeps, **{tool: mine for tool in CASMECH_TOOLS}}
    tools = args.tools
    if args.casmech_commit and len(args.casmech_commit) > 1:
        tools = use_snapshots(args.casmech_commit, args.tools)
    elif args.casmech_commit:
        use_snapshot(args.casmech_commit[0])
    export_models()
    args.out.mkdir(parents=True, exist_ok=True)
    stamp = datetime.datetime.now().strftime("%Y%m%d_%H%M%S")
    log_path = args.out / f"{stamp}.log"

    def log(text: str) -> None:
        print(text, flush=True)
        with open(log_path, "a") as handle:
            handle.write(text + "\n")

    report = {"machine": machine(), "command": " ".join([Path(sys.executable).name,
                                                         *sys.argv]),
              "settings": {k: (str(v) if isinstance(v, Path) else v)
                           for k, v in vars(args).items()},
              "levels": LEVELS, "systems": []}
    log(f"machine: {json.dumps(report['machine'])}")
    json_path = args.out / f"{stamp}.json"
    for name in args.systems:
        report["systems"].append(run_system(name, tools, args, sweeps, log))
        json_path.write_text(json.dumps(report, indent=1))  # after every system
    report["machine"]["loadavg_end"] = os.getloadavg()
    json_path.write_text(json.dumps(report, indent=1))
    from tables import markdown

    md_path = args.out / f"{stamp}.md"
    md_path.write_text(markdown(report))
    for path in (json_path, md_path, log_path):
        shutil.copy(path, args.out / f"latest{path.suffix}")
    log(f"wrote {json_path} and {md_path}")
    print(md_path.read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
