"""Compile time of casmech's code generation: YAML text -> loaded compiled model, by stage, for
chains of N spherical-jointed bars (systems.chain), over optimisation levels and parallel
translation units, for the bundle built from mapped kernels (codegen.mapped: what casmech
compiles) and the unrolled SX bundle (compiler.functions: what it compiled before); plus the
simulation time of each library (and of the interpreted SX bundle).

    python benchmarks/codegen_times.py --bodies 32 128 1000 --repeats 3 --simulate 1
    python benchmarks/codegen_times.py --bodies 32 --forms mapped unrolled interpreted \
        --levels 0 2 --simulate 1

Each setting runs in a fresh process with an empty cache (so nothing is shared), repeated
--repeats times; the table reports medians. Results: RESULTS_codegen.md.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def bundle(form: str, ir) -> dict:
    """What code generation compiles: every system function and the DAE residuals, built from
    mapped kernels (codegen.mapped, what casmech compiles) or unrolled SX (compiler.functions,
    what it compiled before)."""
    from casmech.codegen import generate, mapped
    from casmech.compiler.functions import build_functions

    if form == "mapped":
        return mapped.mapped_functions(ir, residuals=True)
    functions = build_functions(ir).functions
    return {**functions, **generate.dae_functions(functions)}


def worker(bodies: int, flags: str, jobs: int, simulate: float, form: str = "mapped",
           directions: int = 0) -> dict:
    """One setting, in this process: every stage timed."""
    sys.path.insert(0, str(HERE))
    import casmech_model
    import systems

    import casmech
    from casmech import codegen
    from casmech.codegen import build, generate, kernels, load, manifest
    from casmech.compiler.lower import lower

    if directions:
        kernels.MAX_DIRECTIONS = directions

    text = casmech_model.yaml_text(systems.make(f"chain{bodies}"))
    times, clock = {}, time.perf_counter()

    def lap(name: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        times[name], clock = now - clock, now

    model = casmech.loads(text)
    lap("load")
    ir = lower(model)
    functions = bundle(form, ir)
    lap("symbolic")
    chain = codegen.Toolchain(flags=tuple(flags.split()), jobs=jobs)
    with tempfile.TemporaryDirectory() as directory:
        sources = generate.write_sources(functions, Path(directory), jobs)
        lap("generate_c")
        c_bytes = sum(s.stat().st_size for s in sources)
        build.build_library(sources, Path(directory), chain)
        lap("gcc")
        manifest.write(Path(directory), functions, generate.differentiated(functions), {})
        compiled = load.load(Path(directory), ir)
        lap("load_library")
        times["total"] = sum(times.values())
        result = {"bodies": bodies, "flags": flags, "jobs": jobs, "form": form, "times": times,
                  "c_megabytes": c_bytes / 1e6, "directions": kernels.MAX_DIRECTIONS}
        if simulate > 0:
            start = time.perf_counter()
            casmech.analyze(compiled, "dynamics", t_end=simulate, output_step=0.01)
            result["simulate"] = time.perf_counter() - start
    return result


def interpreted_worker(bodies: int, simulate: float) -> dict:
    """YAML -> the interpreted SX bundle, and its simulation (no C)."""
    sys.path.insert(0, str(HERE))
    import casmech_model
    import systems

    import casmech

    start = time.perf_counter()
    functions = casmech.compile(casmech.loads(casmech_model.yaml_text(
        systems.make(f"chain{bodies}"))), "interpreted")
    result = {"bodies": bodies, "flags": "", "jobs": 1, "form": "interpreted",
              "times": {"total": time.perf_counter() - start}, "c_megabytes": 0.0}
    if simulate > 0:
        start = time.perf_counter()
        casmech.analyze(functions, "dynamics", t_end=simulate, output_step=0.01)
        result["simulate"] = time.perf_counter() - start
    return result


def run_setting(bodies: int, flags: str, jobs: int, simulate: float, timeout: float,
                form: str, directions: int = 0) -> dict:
    command = [sys.executable, __file__, "--worker", str(bodies), flags, str(jobs),
               str(simulate), form, str(directions)]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                              check=False, env={**os.environ, "OMP_NUM_THREADS": "1"})
    except subprocess.TimeoutExpired:
        return {"bodies": bodies, "flags": flags, "jobs": jobs, "form": form, "timeout": timeout}
    if done.returncode != 0:
        return {"bodies": bodies, "flags": flags, "jobs": jobs, "form": form,
                "error": done.stderr[-2000:]}
    return json.loads(done.stdout.splitlines()[-1])


def median_row(runs: list[dict]) -> dict:
    good = [r for r in runs if "times" in r]
    if not good:
        return runs[0]
    first = good[0]
    row = {**first, "times": {k: statistics.median(r["times"][k] for r in good)
                              for k in first["times"]}, "repeats": len(good)}
    if "simulate" in first:
        row["simulate"] = statistics.median(r["simulate"] for r in good)
        row["simulate_runs"] = [round(r["simulate"], 3) for r in good]
    row["total_runs"] = [round(r["times"]["total"], 2) for r in good]
    return row


STAGES = ("load", "symbolic", "generate_c", "gcc", "load_library")


def table(rows: list[dict]) -> str:
    lines = ["| bodies | form | flags | jobs | dirs | load | symbolic | generate C | gcc | "
             "load lib | YAML -> loaded s | runs s | C MB | simulation s | runs s |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        head = (f"| {r['bodies']} | {r['form']} | {r['flags']} | {r['jobs']} | "
                f"{r.get('directions', '')} |")
        if "times" not in r:
            why = f"timeout {r['timeout']:.0f} s" if "timeout" in r else "error"
            lines.append(f"{head} {why} |||||||||||")
            continue
        t = r["times"]
        stages = " | ".join(f"{t[k]:.2f}" if k in t else "" for k in STAGES)
        sim = f"{r['simulate']:.2f} | {' '.join(map(str, r['simulate_runs']))}" \
            if "simulate" in r else " | "
        lines.append(f"{head} {stages} | **{t['total']:.2f}** | "
                     f"{' '.join(map(str, r['total_runs']))} | {r['c_megabytes']:.2f} | {sim} |")
    return "\n".join(lines)


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        bodies, flags, jobs, simulate, form, directions = sys.argv[2:8]
        if form == "interpreted":
            print(json.dumps(interpreted_worker(int(bodies), float(simulate))))
        else:
            print(json.dumps(worker(int(bodies), flags, int(jobs), float(simulate), form,
                                    int(directions))))
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bodies", type=int, nargs="+", default=[8, 32])
    parser.add_argument("--forms", nargs="+", default=["mapped"],
                        choices=["mapped", "unrolled", "interpreted"])
    parser.add_argument("--levels", nargs="+", default=["0"],
                        help="gcc optimisation levels to compare (0 1 2 3 s)")
    parser.add_argument("--jobs", type=int, nargs="+", default=[os.cpu_count() or 1])
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--simulate", type=float, default=0.0,
                        help="also time dynamics over this many seconds (0: no)")
    parser.add_argument("--timeout", type=float, default=1800.0)
    parser.add_argument("--directions", type=int, nargs="+", default=[0],
                        help="kernel derivative directions per call (codegen.kernels."
                             "MAX_DIRECTIONS; 0: its value)")
    args = parser.parse_args()
    print(f"# {platform.node()} {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
          f"load average {os.getloadavg()[0]:.1f}", flush=True)
    rows = []
    for bodies in args.bodies:
        for form in args.forms:
            levels = [""] if form == "interpreted" else [f"-O{level}" for level in args.levels]
            for flags in levels:
                for jobs, directions in itertools.product(
                        args.jobs if form != "interpreted" else [1],
                        args.directions if form == "mapped" else [0]):
                    runs = [run_setting(bodies, flags, jobs, args.simulate, args.timeout, form,
                                        directions) for _ in range(args.repeats)]
                    rows.append(median_row(runs))
                    print(json.dumps(rows[-1]), flush=True)
    print(table(rows))


if __name__ == "__main__":
    main()
