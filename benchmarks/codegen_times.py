"""Compile time of casmech's code generation: YAML text -> loaded compiled model, by stage, for
chains of N spherical-jointed bars (systems.chain), over optimisation levels and parallel
translation units, for the bundle built from mapped kernels
(equations.functions.mapped_functions: what casmech compiles) and the inline SX bundle
(equations.functions.build_functions: what it compiled before); plus the simulation time of each
library (and of the interpreted SX bundle).

    python benchmarks/codegen_times.py --bodies 32 128 1000 --repeats 3 --simulate 1
    python benchmarks/codegen_times.py --bodies 32 --forms mapped unrolled interpreted \
        --levels 0 2 --simulate 1
    python benchmarks/codegen_times.py --per-call chain8 chain32 four_bar --levels 1 2 \
        --repeats 3        # CPU us per call of what IDAS and a results row evaluate

Each setting runs in a fresh process with an empty cache (so nothing is shared), repeated
--repeats times; the table reports medians. Results: docs/decisions/codegen-element-residuals.md.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def bundle(form: str, ir) -> tuple[dict, dict]:
    """What code generation compiles: (the system functions, {DAE name: its dae/daeF/jacF}).
    compiled: what casmech builds (equations.functions.mapped_functions: kernels mapped over
    instances, the DAEs as
    sums of elements, formulations.residuals); unrolled: the SX bundle of equations.functions and
    formulations.dae's SX residuals with their SX Jacobians."""
    from casmech.backends import codegen
    from casmech.equations.functions import build_functions, mapped_functions
    from casmech.formulations import dae, residuals

    if form == "compiled":
        return mapped_functions(ir), codegen.dae_oracles(ir)
    functions = build_functions(ir).functions
    return functions, {name: residuals.from_residual(f)
                       for name, f in dae.residuals(functions).items()}


def timed_dynamics(functions, t_end: float) -> dict:
    """casmech.analyze(..., "dynamics") over t_end (output every 0.01 s) in the r-p formulation
    (the one whose DAE is compiled; chains, being trees, default to joint coordinates, whose
    system formulations.joint_system builds and runs interpreted): wall and CPU seconds,
    and from IDAS's own timers (record_time) the time inside the integrations and in its
    daeF/jacF calls, with its step and residual-evaluation counts."""
    import casadi as ca

    import casmech

    made, original = [], ca.integrator

    def recording(*args):
        *head, options = args
        made.append(original(*head, {**options, "record_time": True}))
        return made[-1]

    ca.integrator = recording
    try:
        wall, cpu = time.perf_counter(), time.process_time()
        casmech.analyze(functions, "dynamics", t_end=t_end, output_step=0.01,
                        formulation="rp")
        out = {"simulate": time.perf_counter() - wall, "simulate_cpu": time.process_time() - cpu}
    finally:
        ca.integrator = original
    totals: dict = {}
    for integrator in made:
        for key, value in integrator.stats().items():
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                totals[key] = totals.get(key, 0) + value
    out |= {"idas_s": totals.get("t_proc_total", 0.0), "daeF_s": totals.get("t_proc_daeF", 0.0),
            "jacF_s": totals.get("t_proc_jacF", 0.0), "steps": totals.get("nsteps", 0),
            "residuals": totals.get("nfevals", 0), "jacobians": totals.get("nlinsetups", 0)}
    return out


def system_name(bodies: str) -> str:
    """--bodies N means benchmarks/systems.py's chain<N>; any other name is that system."""
    return f"chain{bodies}" if str(bodies).isdigit() else str(bodies)


def worker(bodies: str, flags: str, jobs: int, simulate: float, form: str = "compiled",
           directions: int = 0) -> dict:
    """One setting, in this process: every stage timed."""
    sys.path.insert(0, str(HERE))
    import casmech_model
    import systems

    import casmech
    from casmech.backends import build, codegen, generate, load, manifest
    from casmech.model.lower import lower
    from casmech.numerics import instances as kernels

    if directions:
        kernels.MAX_DIRECTIONS = directions

    text = casmech_model.yaml_text(systems.make(system_name(bodies)))
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
        children = resource.getrusage(resource.RUSAGE_CHILDREN)
        build.build_libraries({build.LIBRARY: sources, **dae_sources}, Path(directory), chain)
        lap("gcc")
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        gcc_cpu = after.ru_utime + after.ru_stime - children.ru_utime - children.ru_stime
        manifest.write(Path(directory), {**functions, **{n: o[n] for n, o in oracles.items()}},
                       generate.differentiated(functions), {"library": build.LIBRARY},
                       {name: generate.dae_library(name) for name in oracles})
        compiled = load.load(Path(directory), ir)
        lap("load_library")
        times["total"] = sum(times.values())
        result = {"bodies": bodies, "flags": flags, "jobs": jobs, "form": form, "times": times,
                  "c_megabytes": c_bytes / 1e6, "directions": kernels.MAX_DIRECTIONS,
                  "gcc_cpu": gcc_cpu}
        if simulate > 0:
            result |= timed_dynamics(compiled, simulate)
    return result


def interpreted_worker(bodies: str, simulate: float) -> dict:
    """YAML -> the interpreted SX bundle, and its simulation (no C)."""
    sys.path.insert(0, str(HERE))
    import casmech_model
    import systems

    import casmech

    start = time.perf_counter()
    functions = casmech.compile(casmech.loads(casmech_model.yaml_text(
        systems.make(system_name(bodies)))), "interpreted")
    result = {"bodies": bodies, "flags": "", "jobs": 1, "form": "interpreted",
              "times": {"total": time.perf_counter() - start}, "c_megabytes": 0.0}
    if simulate > 0:
        result |= timed_dynamics(functions, simulate)
    return result


# --- per-call costs (--per-call) ---------------------------------------------------------------

ROW_FUNCTIONS = ("phi", "phi_q", "nu", "body_rates", "reactions", "energy")  # per output row


HARNESS = r"""
/* Times one casadi function: from a generated library (dlopen) or, for "@file", a serialized
   casadi Function evaluated by libcasadi (casadi_c_*); the same buffers on every call. */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
typedef long long int casadi_int;
typedef int (*eval_t)(const double**, double**, casadi_int*, double*, int);
typedef int (*work_t)(casadi_int*, casadi_int*, casadi_int*, casadi_int*);
typedef const casadi_int* (*sp_t)(casadi_int);
typedef casadi_int (*n_t)(void);
int casadi_c_push_file(const char*);
int casadi_c_activate(int);
int casadi_c_checkout(void);
int casadi_c_eval(const double**, double**, casadi_int*, double*, int);
int casadi_c_work(casadi_int*, casadi_int*, casadi_int*, casadi_int*);
const casadi_int* casadi_c_sparsity_in(casadi_int);
const casadi_int* casadi_c_sparsity_out(casadi_int);
casadi_int casadi_c_n_in(void);
casadi_int casadi_c_n_out(void);
static int mem0;
static int eval_c(const double** a, double** r, casadi_int* iw, double* w, int m) {
  (void) m;
  return casadi_c_eval(a, r, iw, w, mem0);
}
static void* sym(void* h, const char* f, const char* s) {
  char b[256];
  snprintf(b, 256, "%s%s", f, s);
  void* p = dlsym(h, b);
  if (!p) { fprintf(stderr, "no %s\n", b); exit(1); }
  return p;
}
static casadi_int nnz(const casadi_int* sp) {  /* {nrow, ncol, 1}: dense */
  return sp[2] == 1 ? sp[0] * sp[1] : sp[2 + sp[1]];
}
static double seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}
int main(int argc, char** argv) {
  eval_t ev; work_t wk; sp_t spi, spo; n_t nin, nout;
  if (argc < 4) return 2;
  int calls = atoi(argv[3]);
  if (argv[1][0] == '@') {
    if (casadi_c_push_file(argv[1] + 1)) { fprintf(stderr, "load failed\n"); return 1; }
    casadi_c_activate(0);
    mem0 = casadi_c_checkout();
    ev = eval_c; wk = casadi_c_work; spi = casadi_c_sparsity_in;
    spo = casadi_c_sparsity_out; nin = casadi_c_n_in; nout = casadi_c_n_out;
  } else {
    void* h = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!h) { fprintf(stderr, "%s\n", dlerror()); return 1; }
    ev = (eval_t) sym(h, argv[2], ""); wk = (work_t) sym(h, argv[2], "_work");
    spi = (sp_t) sym(h, argv[2], "_sparsity_in");
    spo = (sp_t) sym(h, argv[2], "_sparsity_out");
    nin = (n_t) sym(h, argv[2], "_n_in"); nout = (n_t) sym(h, argv[2], "_n_out");
  }
  casadi_int sa, sr, si, sw;
  wk(&sa, &sr, &si, &sw);
  const double** arg = malloc(sizeof(double*) * (sa > nin() ? sa : nin()));
  double** res = malloc(sizeof(double*) * (sr > nout() ? sr : nout()));
  casadi_int* iw = malloc(sizeof(casadi_int) * (si + 1));
  double* w = malloc(sizeof(double) * (sw + 1));
  srand(1);
  for (casadi_int i = 0; i < nin(); ++i) {
    casadi_int n = nnz(spi(i));
    double* a = malloc(sizeof(double) * (n + 1));
    for (casadi_int k = 0; k < n; ++k) a[k] = 2.0 * rand() / RAND_MAX - 1;
    arg[i] = a;
  }
  for (casadi_int i = 0; i < nout(); ++i) res[i] = malloc(sizeof(double) * (nnz(spo(i)) + 1));
  if (calls <= 0) {  /* about 20 ms per repetition */
    for (calls = 1; calls < 10000000; calls *= 2) {
      double start = seconds();
      for (int c = 0; c < calls; ++c) ev(arg, res, iw, w, 0);
      if (seconds() - start > 0.02) break;
    }
  }
  double best = 1e30;
  for (int rep = 0; rep < 7; ++rep) {
    double start = seconds();
    for (int c = 0; c < calls; ++c) {
      if (ev(arg, res, iw, w, 0)) { fprintf(stderr, "evaluation failed\n"); return 1; }
    }
    double us = (seconds() - start) * 1e6 / calls;
    if (us < best) best = us;
  }
  printf("%.3f\n", best);
  return 0;
}
"""


def harness(directory: Path) -> Path:
    """The C program that times one function: `harness LIB NAME 0` loads NAME from a generated
    library, `harness @FILE NAME 0` a serialized casadi Function (evaluated by casadi's own
    virtual machine: the interpreted form); both are called with the same buffers, the CPU
    time per call is the minimum over 7 repetitions of ~20 ms each, printed in microseconds."""
    import casadi as ca

    source, binary = directory / "harness.c", directory / "harness"
    source.write_text(HARNESS)
    casadi_dir = Path(ca.__file__).parent
    subprocess.run(["gcc", "-O2", "-o", str(binary), str(source), "-ldl", f"-L{casadi_dir}",
                    "-lcasadi", f"-Wl,-rpath,{casadi_dir}"], check=True)
    return binary


def per_call(binary: Path, target: str, name: str) -> float:
    """CPU microseconds per call of function `name` in `target` (a library, or @file)."""
    done = subprocess.run([str(binary), target, name, "0"], capture_output=True, text=True,
                          check=True)
    return float(done.stdout)


def _library(functions: dict, directory: Path, flags: str) -> tuple[dict, float, float]:
    """Compile functions into one library; (externals, gcc seconds, C megabytes)."""
    import casadi as ca

    from casmech.backends import build
    from casmech.backends.codegen import Toolchain

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
    functions a results row calls, for one form of the code at one -O level (C harness)."""
    sys.path.insert(0, str(HERE))
    import casadi as ca
    import casmech_model
    import systems

    import casmech
    from casmech.backends import build
    from casmech.equations.functions import build_functions, mapped_functions
    from casmech.formulations import dae, residuals
    from casmech.model.lower import lower

    ir = lower(casmech.loads(casmech_model.yaml_text(systems.make(system))))
    out = {"system": system, "form": form, "flags": flags}
    with tempfile.TemporaryDirectory() as name:
        directory = Path(name)
        binary = harness(directory)
        start = time.perf_counter()
        targets = {}
        if form == "interpreted":  # the SX functions, in casadi's virtual machine
            functions = build_functions(ir).functions
            integrator = ca.integrator("i", "idas", dae.problem(dae.residual(
                functions, "rp", "ggl")), 0.0, [0.1])
            chosen = {n: functions[n] for n in ROW_FUNCTIONS}
            chosen |= {n: integrator.get_function(n) for n in ("daeF", "jacF")}
            for n, function in chosen.items():
                function.save(str(directory / f"{n}.casadi"))
                targets[n] = "@" + str(directory / f"{n}.casadi")
        else:
            if form == "mapped":  # what casmech compiled before: MX over kernels, and IDAS's
                # jacF built as an MX graph around the library's jac_dae_ggl_rp
                bundle = mapped_functions(ir)
                residual = dae.residual(bundle, "rp", "ggl")
                chosen = {n: bundle[n] for n in ROW_FUNCTIONS}
                chosen |= {"dae_ggl_rp": residual, "jac_dae_ggl_rp": residual.jacobian()}
            elif form == "unrolled":  # the SX functions and SX DAE, daeF/jacF in the library
                functions = build_functions(ir).functions
                chosen = {n: functions[n] for n in ROW_FUNCTIONS}
                chosen |= residuals.from_residual(dae.residual(functions, "rp", "ggl"))
            else:  # elements: what casmech compiles (mapped bundle, formulations.residuals)
                chosen = {n: mapped_functions(ir)[n] for n in ROW_FUNCTIONS}
                chosen |= residuals.oracle(ir, "rp", "ggl")
            loaded, out["gcc_s"], out["c_mb"] = _library(chosen, directory / "lib", flags)
            library = str(directory / "lib" / build.LIBRARY)
            targets = {n: library for n in (*ROW_FUNCTIONS, "daeF", "jacF")}
            if form == "mapped":
                integrator = ca.integrator("i", "idas", dae.problem(loaded["dae_ggl_rp"]), 0.0,
                                           [0.1])
                for n in ("daeF", "jacF"):
                    integrator.get_function(n).save(str(directory / f"{n}.casadi"))
                    targets[n] = "@" + str(directory / f"{n}.casadi")
        out["build_s"] = time.perf_counter() - start
        for n, target in targets.items():
            out[n] = per_call(binary, target, n)
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


def run_setting(bodies: str, flags: str, jobs: int, simulate: float, timeout: float,
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
    if "gcc_cpu" in first:
        row["gcc_cpu"] = statistics.median(r["gcc_cpu"] for r in good)
    if "simulate" in first:
        for key in ("simulate", "simulate_cpu", "idas_s", "daeF_s", "jacF_s", "steps"):
            row[key] = statistics.median(r[key] for r in good)
        row["simulate_runs"] = [round(r["simulate"], 3) for r in good]
    row["total_runs"] = [round(r["times"]["total"], 2) for r in good]
    return row


STAGES = ("load", "symbolic", "generate_c", "gcc", "load_library")


def table(rows: list[dict]) -> str:
    lines = ["| system | form | flags | jobs | load | symbolic | generate C | gcc | load lib | "
             "YAML -> loaded s | runs s | gcc CPU s | C MB | simulation s | runs s | CPU s | "
             "IDAS s | daeF s | jacF s | steps |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        head = f"| {system_name(r['bodies'])} | {r['form']} | {r['flags']} | {r['jobs']} |"
        if "times" not in r:
            why = f"timeout {r['timeout']:.0f} s" if "timeout" in r else "error"
            lines.append(f"{head} {why} |||||||||||||||")
            continue
        t = r["times"]
        stages = " | ".join(f"{t[k]:.2f}" if k in t else "" for k in STAGES)
        sim = (f"{r['simulate']:.2f} | {' '.join(map(str, r['simulate_runs']))} | "
               f"{r['simulate_cpu']:.2f} | {r['idas_s']:.3f} | {r['daeF_s']:.3f} | "
               f"{r['jacF_s']:.3f} | {r['steps']:.0f}") if "simulate" in r else " | | | | | |"
        gcc_cpu = f"{r['gcc_cpu']:.2f}" if "gcc_cpu" in r else ""
        lines.append(f"{head} {stages} | **{t['total']:.2f}** | "
                     f"{' '.join(map(str, r['total_runs']))} | {gcc_cpu} | "
                     f"{r['c_megabytes']:.2f} | {sim} |")
    return "\n".join(lines)


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--per-call-worker":
        print(json.dumps(per_call_worker(*sys.argv[2:5])))
        return
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        bodies, flags, jobs, simulate, form, directions = sys.argv[2:8]
        if form == "interpreted":
            print(json.dumps(interpreted_worker(bodies, float(simulate))))
        else:
            print(json.dumps(worker(bodies, flags, int(jobs), float(simulate), form,
                                    int(directions))))
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bodies", nargs="+", default=["8", "32"],
                        help="chain sizes (benchmarks/systems.py chain<N>) or system names")
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
                        help="kernel derivative directions per call (numerics.instances."
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
