"""Compile time of casmech's code generation: YAML text -> loaded compiled model, by stage, for
chains of N spherical-jointed bars (systems.chain), over optimisation levels and parallel
translation units, for the bundle built from mapped kernels (codegen.mapped: what casmech
compiles) and the unrolled SX bundle (compiler.functions: what it compiled before); plus the
simulation time of each library (and of the interpreted SX bundle).

    python benchmarks/codegen_times.py --bodies 32 128 1000 --repeats 3 --simulate 1
    python benchmarks/codegen_times.py --bodies 32 --forms mapped unrolled interpreted \
        --levels 0 2 --simulate 1
    python benchmarks/codegen_times.py --per-call chain8 chain32 four_bar --levels 1 2 \
        --repeats 3        # CPU us per call of what IDAS and a results row evaluate

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


def bundle(form: str, ir) -> tuple[dict, dict]:
    """What code generation compiles: (the system functions, {DAE name: its dae/daeF/jacF}).
    compiled: what casmech builds (codegen.mapped's kernels mapped over instances, the DAEs as
    sums of elements, codegen.residuals); unrolled: the SX bundle of compiler.functions and
    compiler.dae's SX residuals with their SX Jacobians."""
    from casmech import codegen
    from casmech.codegen import mapped, residuals
    from casmech.compiler import dae
    from casmech.compiler.functions import build_functions

    if form == "compiled":
        return mapped.mapped_functions(ir), codegen.dae_oracles(ir)
    functions = build_functions(ir).functions
    return functions, {name: residuals.from_residual(f)
                       for name, f in dae.residuals(functions).items()}


def worker(bodies: int, flags: str, jobs: int, simulate: float, form: str = "compiled",
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
    functions, oracles = bundle(form, ir)
    lap("symbolic")
    chain = codegen.Toolchain(flags=tuple(flags.split()), jobs=jobs)
    with tempfile.TemporaryDirectory() as directory:
        sources = generate.write_sources(functions, Path(directory), jobs)
        dae_sources = generate.write_dae_sources(oracles, Path(directory))
        lap("generate_c")
        c_bytes = sum(s.stat().st_size for s in sources) + sum(
            s.stat().st_size for group in dae_sources.values() for s in group)
        build.build_libraries({build.LIBRARY: sources, **dae_sources}, Path(directory), chain)
        lap("gcc")
        manifest.write(Path(directory), {**functions, **{n: o[n] for n, o in oracles.items()}},
                       generate.differentiated(functions), {"library": build.LIBRARY},
                       {name: generate.dae_library(name) for name in oracles})
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


# --- per-call costs (--per-call) ---------------------------------------------------------------

ROW_FUNCTIONS = ("phi", "phi_q", "nu", "body_rates", "reactions", "energy")  # per output row


def per_call(function, seconds: float = 0.2, repeats: int = 5) -> float:
    """Median CPU microseconds of one evaluation: `function` mapped over many copies of one
    random input (casadi's serial map, so no Python between calls), timed by process time."""
    import casadi as ca
    import numpy as np

    rng = np.random.default_rng(0)
    args = [ca.DM(function.sparsity_in(k), rng.uniform(-1, 1, function.nnz_in(k)))
            for k in range(function.n_in())]

    def timed(count: int) -> float:
        mapped = function.map(count, "serial")
        big = [ca.repmat(a, 1, count) for a in args]
        mapped.call(big)
        start = time.process_time()
        mapped.call(big)
        return time.process_time() - start

    count = 1
    while count < 2000 and timed(count) < 0.02:
        count *= 4
    count = max(1, min(2000, int(count * seconds / max(timed(count), 1e-6))))
    return statistics.median(timed(count) / count * 1e6 for _ in range(repeats))


def integrator_functions(dae) -> tuple:
    """IDAS's own residual and Jacobian functions (daeF, jacF) for a DAE problem: what the
    integrator evaluates at each Newton iteration and each Jacobian update."""
    import casadi as ca

    integrator = ca.integrator("idas", "idas", dae, 0.0, [0.1])
    return integrator.get_function("daeF"), integrator.get_function("jacF")


def _library(functions: dict, directory: Path, flags: str) -> tuple[dict, float, float]:
    """Compile functions into one library; (externals, gcc seconds, C megabytes)."""
    import casadi as ca

    from casmech.codegen import Toolchain, build

    generator = ca.CodeGenerator("unit.c", {"with_header": False, "verbose": False})
    for function in functions.values():
        generator.add(function)
    directory.mkdir(parents=True, exist_ok=True)
    generator.generate(str(directory) + "/")
    start = time.perf_counter()
    build.build_library([directory / "unit.c"], directory,
                        Toolchain(flags=tuple(flags.split()), jobs=1))
    seconds = time.perf_counter() - start
    library = str(directory / build.LIBRARY)
    megabytes = (directory / "unit.c").stat().st_size / 1e6
    return ({name: ca.external(name, library) for name in functions}, seconds, megabytes)


def per_call_worker(system: str, form: str, flags: str) -> dict:
    """Per-call CPU microseconds of IDAS's daeF and jacF for the r-p GGL DAE and of the
    functions a results row calls, for one form of the bundle at one -O level."""
    sys.path.insert(0, str(HERE))
    import casmech_model
    import systems

    import casmech
    from casmech.codegen import mapped, residuals
    from casmech.compiler import dae
    from casmech.compiler.functions import build_functions
    from casmech.compiler.lower import lower

    ir = lower(casmech.loads(casmech_model.yaml_text(systems.make(system))))
    out = {"system": system, "form": form, "flags": flags}
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as directory:
        if form == "interpreted":
            rows = build_functions(ir).functions
            problem = dae.problem(dae.residual(rows, "rp", "ggl"))
        elif form == "mapped":  # what casmech compiled until this change: MX over kernels
            bundle = mapped.mapped_functions(ir)
            bundle["dae_ggl_rp"] = dae.residual(bundle, "rp", "ggl")
            chosen = {name: bundle[name] for name in (*ROW_FUNCTIONS, "dae_ggl_rp")}
            chosen["jac_dae_ggl_rp"] = bundle["dae_ggl_rp"].jacobian()
            rows, out["gcc_s"], out["c_mb"] = _library(chosen, Path(directory), flags)
            problem = dae.problem(rows["dae_ggl_rp"])
        elif form == "unrolled":  # the SX bundle and the SX DAE, with jacF in the library
            sx = build_functions(ir).functions
            chosen = {name: sx[name] for name in ROW_FUNCTIONS}
            chosen |= residuals.from_residual(dae.residual(sx, "rp", "ggl"))
            rows, out["gcc_s"], out["c_mb"] = _library(chosen, Path(directory), flags)
            problem = rows["dae_ggl_rp"]
        else:  # elements: the mapped bundle's functions, the DAE of codegen.residuals
            bundle = mapped.mapped_functions(ir)
            chosen = {name: bundle[name] for name in ROW_FUNCTIONS}
            chosen |= residuals.oracle(ir, "rp", "ggl")
            rows, out["gcc_s"], out["c_mb"] = _library(chosen, Path(directory), flags)
            problem = rows["dae_ggl_rp"]
        out["build_s"] = time.perf_counter() - start
        dae_f, jac_f = integrator_functions(problem)
        out["daeF"], out["jacF"] = per_call(dae_f), per_call(jac_f)
        out["jacF_class"] = jac_f.class_name()
        out |= {name: per_call(rows[name]) for name in ROW_FUNCTIONS}
    return out


def per_call_table(rows: list[dict]) -> str:
    lines = ["| system | form | flags | build s | gcc s | C MB | daeF us | jacF us | "
             + " | ".join(f"{n} us" for n in ROW_FUNCTIONS) + " |",
             "|---|---|---|---|---|---|---|---|" + "---|" * len(ROW_FUNCTIONS)]
    for r in rows:
        if "daeF" not in r:
            lines.append(f"| {r['system']} | {r['form']} | {r['flags']} | failed |")
            continue
        cells = [f"{r['build_s']:.2f}", f"{r['gcc_s']:.2f}" if "gcc_s" in r else "",
                 f"{r['c_mb']:.2f}" if "c_mb" in r else "", f"{r['daeF']:.2f}",
                 f"{r['jacF']:.1f}", *(f"{r[n]:.2f}" for n in ROW_FUNCTIONS)]
        lines.append(f"| {r['system']} | {r['form']} | {r['flags']} | " + " | ".join(cells)
                     + " |")
    return "\n".join(lines)


def run_per_call(system: str, form: str, flags: str, timeout: float) -> dict:
    command = [sys.executable, __file__, "--per-call-worker", system, form, flags]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                              check=False, env={**os.environ, "OMP_NUM_THREADS": "1"})
    except subprocess.TimeoutExpired:
        return {"system": system, "form": form, "flags": flags, "timeout": timeout}
    if done.returncode != 0:
        return {"system": system, "form": form, "flags": flags, "error": done.stderr[-2000:]}
    return json.loads(done.stdout.splitlines()[-1])


def median_per_call(runs: list[dict]) -> dict:
    good = [r for r in runs if "daeF" in r]
    if not good:
        return runs[0]
    keys = [k for k, v in good[0].items() if isinstance(v, float)]
    return {**good[0], **{k: statistics.median(r[k] for r in good) for k in keys},
            "repeats": len(good)}


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
    if len(sys.argv) > 1 and sys.argv[1] == "--per-call-worker":
        print(json.dumps(per_call_worker(*sys.argv[2:5])))
        return
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
    parser.add_argument("--forms", nargs="+", default=["compiled"],
                        choices=["compiled", "unrolled", "interpreted"])
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
    parser.add_argument("--per-call", nargs="+", metavar="SYSTEM",
                        help="instead: per-call costs of IDAS's daeF/jacF and the row functions "
                             "on these systems (chain<N>, four_bar), for --per-call-forms")
    parser.add_argument("--per-call-forms", nargs="+",
                        default=["interpreted", "mapped", "unrolled", "elements"],
                        choices=["interpreted", "mapped", "unrolled", "elements"])
    args = parser.parse_args()
    if args.per_call:
        rows = []
        for system in args.per_call:
            for form in args.per_call_forms:
                levels = [""] if form == "interpreted" else [f"-O{lv}" for lv in args.levels]
                for flags in levels:
                    runs = [run_per_call(system, form, flags, args.timeout)
                            for _ in range(args.repeats)]
                    rows.append(median_per_call(runs))
                    print(json.dumps(rows[-1]), flush=True)
        print(per_call_table(rows))
        return
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
                        args.directions if form == "compiled" else [0]):
                    runs = [run_setting(bodies, flags, jobs, args.simulate, args.timeout, form,
                                        directions) for _ in range(args.repeats)]
                    rows.append(median_row(runs))
                    print(json.dumps(rows[-1]), flush=True)
    print(table(rows))


if __name__ == "__main__":
    main()
