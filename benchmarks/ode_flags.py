"""The compiled joint system at several C optimization levels: one evaluation of the tree's
ODE (or the loops' DAE) and of the results rows in C, the compiled repeated dynamics call,
and the cold build (docs/decisions/codegen-flags.md).

    python benchmarks/ode_flags.py /tmp/exp/ur5/ur5.yaml:1e-5 chain8:1e-7 four_bar:1e-4 \
        --flags=-O1,-O2,-O3 --rounds 3

Each target (a model file or a benchmark system, `:rtol` its call's rtol, atol = rtol / 100)
runs in a process of its own per flag set and round, the flag sets alternating within each
round, each process on an empty cache folder of its own:

- cold build: `casmech.compile(model, "compiled")` and the first `casmech.analyze(functions,
  "dynamics", t_end=1, rtol=r, atol=r/100)` (which builds the joint system's library), wall
  and CPU with the compilers' (robots.py's measure);
- again: the same analyze repeated `--calls` times, the median CPU;
- C: the joint system's dynamics (joint_ode or joint_dae) and results rows (joint_motion)
  called in a loop in a C program (gcc -O2) at the start's state, CPU per call.

`--scope joint` sets the flags of the joint system's ODE and rows only (LOOP: their units
in backends.joint_library's toolchain; the rest as by default); `--scope all` every library the
default flags build (build.DEFAULT_FLAGS; the joint tree's deferred bundle stays at -O0 as by
default). The first flag set's results table is the one the others are compared with (largest
absolute difference).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import c_timing  # noqa: E402

HERE = Path(__file__).resolve().parent
FLAGS_VARIABLE = "ODE_FLAGS_CHILD"  # a child process's flag set
# the joint system's functions a run calls in its loops: the integrator's right-hand side, the
# results rows once per output row (--scope joint)
LOOP = ("joint_ode", "joint_dae", "joint_motion", "joint_solved_motion")
# the timing program's main, after c_timing.PRELUDE
HARNESS = r"""
/* lib symbol calls n_in nnz_in... n_out nnz_out... sz_iw sz_w values-file */
int main(int argc, char** argv) {
  int a = 1;
  void* lib = dlopen(argv[a++], RTLD_NOW);
  fn g = (fn)dlsym(lib, argv[a++]);
  long calls = atol(argv[a++]);
  int n_in = atoi(argv[a++]);
  const double* arg[64]; double* in[64]; double* res[64];
  for (int i = 0; i < n_in; i++) in[i] = calloc(atoi(argv[a++]) + 1, 8);
  int n_out = atoi(argv[a++]);
  for (int i = 0; i < n_out; i++) res[i] = calloc(atoi(argv[a++]) + 1, 8);
  ci* iw = calloc(atol(argv[a++]) + 1, 8);
  double* w = calloc(atol(argv[a++]) + 1, 8);
  FILE* values = fopen(argv[a++], "r");
  for (int i = 0; i < n_in; i++) {
    int k; if (fscanf(values, "%d", &k) != 1) return 1;
    for (int j = 0; j < k; j++) if (fscanf(values, "%lf", &in[i][j]) != 1) return 1;
    arg[i] = in[i];
  }
  double s = 0, start = now();
  for (long k = 0; k < calls; k++) { in[1][0] += 1e-15; g(arg, res, iw, w, 0); s += res[0][0]; }
  printf("%.6g %g\n", (now() - start) / calls, s);
  return 0;
}
"""


def _cpu() -> float:
    own, children = (resource.getrusage(who) for who in (resource.RUSAGE_SELF,
                                                         resource.RUSAGE_CHILDREN))
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def _model(target: str):
    import casmech

    if target.endswith(".yaml"):
        return casmech.load(target)
    sys.path.insert(0, str(HERE))
    from casmech_model import yaml_text
    from systems import make

    return casmech.loads(yaml_text(make(target)), file=f"<{target}>")


def _set_flags(scope: str, flags: tuple[str, ...]) -> None:
    from casmech.backends import build, deferred, joint_library

    if scope == "all":
        build.DEFAULT_FLAGS = deferred.DEFAULT_FLAGS = flags
        return
    chosen = joint_library.toolchain

    def toolchain(instructions: int, quick_build_instructions: int, names=()
                  ) -> build.Toolchain:
        """joint_library's toolchain with the LOOP functions' units at `flags` (the machine's
        instruction set only where `flags` name it) where it builds at the default flags (no
        flags chosen, the ODE below the quick build's size)."""
        made = chosen(instructions, quick_build_instructions, names)
        default = build.DEFAULT_FLAGS + joint_library.machine()
        if joint_library.chosen_flags() is not None or made.flags != default:
            return made
        return build.Toolchain(made.compiler, made.flags, made.jobs, made.function_flags
                               + tuple((name, flags) for name in LOOP))

    joint_library.toolchain = toolchain  # runtime.joint_dynamics imports it on each use


def _c_time(harness: Path, function, values: list[np.ndarray], calls: int) -> float:
    from casmech.backends import external_record

    with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as file:
        file.write(" ".join(f"{len(v)} " + " ".join(repr(float(x)) for x in v)
                            for v in values))
    try:
        args = [str(external_record.library(function)), function.name(), str(calls),
                str(function.n_in()), *(str(function.nnz_in(i)) for i in range(function.n_in())),
                str(function.n_out()),
                *(str(function.nnz_out(i)) for i in range(function.n_out())),
                str(function.sz_iw()), str(function.sz_w()), file.name]
        return statistics.median(float(subprocess.run(
            [str(harness), *args], capture_output=True, text=True, check=True).stdout.split()[0])
            for _ in range(5))
    finally:
        os.unlink(file.name)


def child(target: str, rtol: float, scope: str, flags: tuple[str, ...], calls: int,
          harness: Path, table: Path) -> dict:
    import casmech
    from casmech.runtime import joint_dynamics
    from casmech.runtime.workspace import of

    _set_flags(scope, flags)
    model = _model(target)
    wall, cpu = time.perf_counter(), _cpu()
    functions = casmech.compile(model, "compiled")
    result = casmech.analyze(functions, "dynamics", t_end=1.0, rtol=rtol, atol=rtol / 100)
    out = {"build_wall": time.perf_counter() - wall, "build_cpu": _cpu() - cpu}
    np.save(table, result.to_dataframe().to_numpy())
    again = []
    for _ in range(calls):
        start = time.process_time()
        casmech.analyze(functions, "dynamics", t_end=1.0, rtol=rtol, atol=rtol / 100)
        again.append(time.process_time() - start)
    out["again"] = statistics.median(again)
    workspace = of(functions, None)
    settings = joint_dynamics.DEFAULT
    system = joint_dynamics.joint_system(functions, settings, workspace)
    x0 = np.asarray(joint_dynamics._kept_start(functions, system, 0.0, settings.assembly,
                                               workspace)[0], float).ravel()
    for label, function in (("ode", system.dynamics), ("motion", system.motion)):
        values = [np.full(function.nnz_in(i), 0.3) for i in range(function.n_in())]
        if function.nnz_in(1) == len(x0):
            values[1] = x0
        try:
            out[label] = _c_time(harness, function, values, 20_000)
        except (KeyError, TypeError, AttributeError, subprocess.CalledProcessError):
            out[label] = float("nan")  # not one compiled external (halves, interpreted)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("targets", nargs="*", help="model files or benchmark systems, each "
                        "with :rtol")
    parser.add_argument("--flags", default="-O1,-O2,-O3", help="flag sets, comma-separated "
                        "(--flags=-O1,-O2 -fno-math-errno)")
    parser.add_argument("--scope", choices=("joint", "all"), default="joint")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--calls", type=int, default=20)
    parser.add_argument("--child", nargs=4, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        target, rtol, harness, table = args.child
        flags = os.environ[FLAGS_VARIABLE]
        print(json.dumps(child(target, float(rtol), args.scope, tuple(flags.split()),
                               args.calls, Path(harness), Path(table))))
        return
    with tempfile.TemporaryDirectory(prefix="casmech_ode_flags_") as folder:
        harness = c_timing.build(Path(folder), HARNESS)
        for n, spec in enumerate(args.targets):
            target, rtol = spec.rsplit(":", 1)
            runs: dict[str, list[dict]] = {flags: [] for flags in args.flags.split(",")}
            tables: dict[str, np.ndarray] = {}
            for k in range(args.rounds):
                for flags in runs:
                    cache = Path(folder) / f"cache_{n}_{k}_{list(runs).index(flags)}"
                    table = Path(folder) / "table.npy"
                    done = subprocess.run(
                        [sys.executable, __file__, "--scope", args.scope, "--calls",
                         str(args.calls), "--child", target, rtol, str(harness), str(table)],
                        env={**os.environ, "CASMECH_CACHE_DIR": str(cache), FLAGS_VARIABLE: flags,
                             "CASMECH_BACKGROUND_BUILD": "0"},
                        check=True, capture_output=True, text=True)
                    runs[flags].append(json.loads(done.stdout.splitlines()[-1]))
                    tables.setdefault(flags, np.load(table))
            first = tables[next(iter(runs))]
            print(f"{target} rtol {rtol} (scope {args.scope}, medians of {args.rounds}, "
                  f"load {os.getloadavg()[0]:.1f}):")
            for flags, rows in runs.items():
                m = {key: statistics.median(r[key] for r in rows) for key in rows[0]}
                differ = float(np.max(np.abs(tables[flags] - first))) if (
                    tables[flags].shape == first.shape) else float("nan")
                print(f"  {flags:<24} ODE {1e6 * m['ode']:.3f} us, rows {1e6 * m['motion']:.3f}"
                      f" us, again {1e3 * m['again']:.3f} ms, cold build "
                      f"{m['build_wall']:.2f} s wall ({m['build_cpu']:.2f} CPU); table "
                      f"differs by {differ:.3g}")


if __name__ == "__main__":
    main()
