"""Compile time of casmech's code generation: YAML text -> loaded compiled model, by stage, for
chains of N spherical-jointed bars (systems.chain), over optimisation levels and parallel
translation units; plus the warm-cache time and simulation speed compiled vs interpreted.

    python benchmarks/codegen_times.py --bodies 8 32 128 --levels 0 1 --jobs 1 2
    python benchmarks/codegen_times.py --bodies 32 --simulate 0.2      # also time dynamics
    python benchmarks/codegen_times.py --kernels --bodies 32 128 1000  # constraint functions:
                                         # kernel-mapped (codegen.kernels) vs unrolled

Each setting runs in a fresh process with an empty cache (so nothing is shared), repeated
--repeats times; the table reports medians. Results: RESULTS_codegen.md.
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
from pathlib import Path

HERE = Path(__file__).resolve().parent


def worker(bodies: int, flags: str, jobs: int, simulate: float) -> dict:
    """One setting, in this process: every stage timed."""
    sys.path.insert(0, str(HERE))
    import casmech_model
    import systems

    import casmech
    from casmech import codegen
    from casmech.codegen import build, generate, load, manifest
    from casmech.compiler.functions import build_functions
    from casmech.compiler.lower import lower

    text = casmech_model.yaml_text(systems.make(f"chain{bodies}"))
    times, clock = {}, time.perf_counter()

    def lap(name: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        times[name], clock = now - clock, now

    model = casmech.loads(text)
    lap("load")
    symbolic = build_functions(lower(model))
    functions = {**symbolic.functions, **generate.dae_functions(symbolic.functions)}
    lap("symbolic")  # what codegen.compiled builds: the bundle and the DAE residuals
    chain = codegen.Toolchain(flags=tuple(flags.split()), jobs=jobs)
    with tempfile.TemporaryDirectory() as directory:
        sources = generate.write_sources(functions, Path(directory), jobs)
        lap("generate_c")
        c_bytes = sum(s.stat().st_size for s in sources)
        build.build_library(sources, Path(directory), chain)
        lap("gcc")
        manifest.write(Path(directory), functions, generate.differentiated(functions), {})
        compiled = load.load(Path(directory), lower(model))
        lap("load_library")
        times["total"] = sum(times.values())
        instructions = sum(f.n_instructions() for group in generate.units(functions)
                           .values() for f in group)
        result = {"bodies": bodies, "flags": flags, "jobs": jobs, "times": times,
                  "c_megabytes": c_bytes / 1e6, "instructions": instructions}
        if simulate > 0:
            for mode, functions in (("interpreted", symbolic), ("compiled", compiled)):
                start = time.perf_counter()
                casmech.analyze(functions, "dynamics", t_end=simulate, output_step=0.01)
                result[f"simulate_{mode}"] = time.perf_counter() - start
    return result


def _timed_build(functions: dict, directory: Path, flags: str) -> tuple[float, float, dict]:
    """(generate C s, gcc s, name -> loaded external) of functions in one translation unit."""
    import casadi as ca

    from casmech import codegen
    from casmech.codegen import build

    start = time.perf_counter()
    code = ca.CodeGenerator("constraints.c")
    for function in functions.values():
        code.add(function)
    code.generate(str(directory) + "/")
    generated = time.perf_counter() - start
    library = build.build_library([directory / "constraints.c"], directory,
                                  codegen.Toolchain(flags=tuple(flags.split()), jobs=1))
    compiled = time.perf_counter() - start - generated
    return generated, compiled, {n: ca.external(n, str(library)) for n in functions}


def kernel_worker(bodies: int, flags: str) -> dict:
    """phi, phi_q, nu, gamma: unrolled SX (compiler.assemble) vs kernel-mapped
    (codegen.kernels): build, C generation, gcc, and microseconds per call."""
    sys.path.insert(0, str(HERE))
    import casadi as ca
    import casmech_model
    import numpy as np
    import systems

    import casmech
    from casmech.codegen import kernels
    from casmech.compiler.assemble import build_constraints
    from casmech.compiler.lower import lower

    ir = lower(casmech.loads(casmech_model.yaml_text(systems.make(f"chain{bodies}"))))

    def unrolled() -> dict:
        cs = build_constraints(ir)
        t, q, q_dot = cs.x.t, cs.x.q, cs.x.q_dot
        return {"phi": ca.Function("phi", [t, q], [cs.phi]),
                "phi_q": ca.Function("phi_q", [t, q], [cs.phi_q]),
                "nu": ca.Function("nu", [t, q], [cs.nu]),
                "gamma": ca.Function("gamma", [t, q, q_dot], [cs.gamma])}

    rng = np.random.default_rng(0)
    args = {"phi_q": (0.3, rng.uniform(-1, 1, 7 * bodies)),
            "gamma": (0.3, rng.uniform(-1, 1, 7 * bodies), rng.uniform(-1, 1, 7 * bodies))}
    result = {"bodies": bodies, "flags": flags}
    for label, make in (("unrolled", unrolled),
                        ("kernels", lambda: kernels.constraint_functions(ir))):
        start = time.perf_counter()
        functions = make()
        symbolic = time.perf_counter() - start
        with tempfile.TemporaryDirectory() as directory:
            generated, compiled, loaded = _timed_build(functions, Path(directory), flags)
            calls = {}
            for name, inputs in args.items():
                repeats = max(20, 100000 // bodies)
                start = time.perf_counter()
                for _ in range(repeats):
                    loaded[name](*inputs)
                calls[name] = 1e6 * (time.perf_counter() - start) / repeats
        result[label] = {"symbolic": symbolic, "generate_c": generated, "gcc": compiled,
                         "microseconds": calls}
    return result


def kernel_table(rows: list[dict]) -> str:
    lines = ["| bodies | flags | form | symbolic s | generate C s | gcc s | total s | "
             "phi_q us/call | gamma us/call |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        for form in ("unrolled", "kernels"):
            if form not in r:
                lines.append(f"| {r['bodies']} | {r['flags']} | {form} | "
                             f"{'timeout' if 'timeout' in r else 'error'} |||||")
                continue
            f = r[form]
            total = f["symbolic"] + f["generate_c"] + f["gcc"]
            lines.append(f"| {r['bodies']} | {r['flags']} | {form} | {f['symbolic']:.2f} | "
                         f"{f['generate_c']:.2f} | {f['gcc']:.2f} | {total:.2f} | "
                         f"{f['microseconds']['phi_q']:.0f} | {f['microseconds']['gamma']:.0f} |")
    return "\n".join(lines)


def run_setting(bodies: int, flags: str, jobs: int, simulate: float, timeout: float,
                kernels: bool = False) -> dict:
    command = [sys.executable, __file__, "--kernel-worker" if kernels else "--worker",
               str(bodies), flags, str(jobs), str(simulate)]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                              check=False, env={**os.environ, "OMP_NUM_THREADS": "1"})
    except subprocess.TimeoutExpired:
        return {"bodies": bodies, "flags": flags, "jobs": jobs, "timeout": timeout}
    if done.returncode != 0:
        return {"bodies": bodies, "flags": flags, "jobs": jobs, "error": done.stderr[-2000:]}
    return json.loads(done.stdout.splitlines()[-1])


def median_row(runs: list[dict]) -> dict:
    first = runs[0]
    if "times" not in first:
        return first
    row = {**first, "times": {k: statistics.median(r["times"][k] for r in runs)
                              for k in first["times"]}, "repeats": len(runs)}
    for key in ("simulate_interpreted", "simulate_compiled"):
        if key in first:
            row[key] = statistics.median(r[key] for r in runs)
    return row


def table(rows: list[dict]) -> str:
    lines = ["| bodies | flags | jobs | load | symbolic | generate C | gcc | load lib | total "
             "| C MB | SX instructions | sim interp. | sim compiled |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "times" not in r:
            why = f"timeout {r['timeout']:.0f} s" if "timeout" in r else "error"
            lines.append(f"| {r['bodies']} | {r['flags']} | {r['jobs']} | {why} |||||||||")
            continue
        t = r["times"]
        sim = [f"{r[k]:.2f}" if k in r else "" for k in ("simulate_interpreted",
                                                          "simulate_compiled")]
        lines.append(f"| {r['bodies']} | {r['flags']} | {r['jobs']} | {t['load']:.2f} | "
                     f"{t['symbolic']:.2f} | {t['generate_c']:.2f} | {t['gcc']:.2f} | "
                     f"{t['load_library']:.2f} | {t['total']:.2f} | {r['c_megabytes']:.2f} | "
                     f"{r['instructions']} | {sim[0]} | {sim[1]} |")
    return "\n".join(lines)


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        bodies, flags, jobs, simulate = sys.argv[2:6]
        print(json.dumps(worker(int(bodies), flags, int(jobs), float(simulate))))
        return
    if len(sys.argv) > 1 and sys.argv[1] == "--kernel-worker":
        print(json.dumps(kernel_worker(int(sys.argv[2]), sys.argv[3])))
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bodies", type=int, nargs="+", default=[8, 32])
    parser.add_argument("--levels", nargs="+", default=["1"],
                        help="gcc optimisation levels to compare (0 1 2 3 s)")
    parser.add_argument("--jobs", type=int, nargs="+", default=[os.cpu_count() or 1])
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--simulate", type=float, default=0.0,
                        help="also time dynamics over this many seconds (0: no)")
    parser.add_argument("--timeout", type=float, default=1800.0)
    parser.add_argument("--kernels", action="store_true",
                        help="compare kernel-mapped and unrolled constraint functions instead")
    args = parser.parse_args()
    print(f"# {platform.node()} {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
          flush=True)
    rows = []
    if args.kernels:
        for bodies in args.bodies:
            for flags in (f"-O{level}" for level in args.levels):
                rows.append(run_setting(bodies, flags, 1, 0.0, args.timeout, kernels=True))
                print(json.dumps(rows[-1]), flush=True)
        print(kernel_table(rows))
        return
    for bodies in args.bodies:
        for flags in (f"-O{level}" for level in args.levels):
            for jobs in args.jobs:
                runs = [run_setting(bodies, flags, jobs, args.simulate, args.timeout)
                        for _ in range(args.repeats)]
                rows.append(median_row(runs))
                print(json.dumps(rows[-1]), flush=True)
    print(table(rows))


if __name__ == "__main__":
    main()
