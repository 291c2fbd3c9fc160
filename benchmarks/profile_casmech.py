"""Where casmech's time goes: cProfile of one casmech.analyze run, grouped.

    python benchmarks/profile_casmech.py chain8 --rtol 1e-12
    python benchmarks/profile_casmech.py chain2 --rtol 1e-8 --top 15

Prints the top functions by own time and by cumulative time, then a coarse split: time inside
CasADi Function calls (IDAS integrations and the SX function evaluations made from Python), time
constructing CasADi integrators, NumPy linear algebra, and the rest (Python)."""

from __future__ import annotations

import os

# single-threaded BLAS, as run.py's workers (must precede the NumPy import)
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import argparse  # noqa: E402
import cProfile  # noqa: E402
import io  # noqa: E402
import pstats  # noqa: E402
import time  # noqa: E402

from casmech_model import Runner  # noqa: E402
from systems import OUTPUT_STEP, T_END, make  # noqa: E402


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("system")
    parser.add_argument("--rtol", type=float, default=1e-12)
    parser.add_argument("--atol", type=float, help="default rtol / 100")
    parser.add_argument("--t-end", type=float, default=T_END)
    parser.add_argument("--top", type=int, default=12)
    args = parser.parse_args(argv)
    import casmech

    runner = Runner(make(args.system))
    atol = args.atol if args.atol is not None else args.rtol * 1e-2
    profile = cProfile.Profile()
    start = time.perf_counter()
    profile.enable()
    result = casmech.analyze(runner.functions, "dynamics", t_end=args.t_end,
                             output_step=OUTPUT_STEP, rtol=args.rtol, atol=atol)
    profile.disable()
    wall = time.perf_counter() - start
    print(f"{args.system}: rtol={args.rtol:g} atol={atol:g}, t_end={args.t_end:g}: {wall:.2f} s "
          f"(build {runner.build_time}); metadata {result.metadata}")
    for key in ("tottime", "cumulative"):
        text = io.StringIO()
        pstats.Stats(profile, stream=text).sort_stats(key).print_stats(args.top)
        print(text.getvalue())
    stats = pstats.Stats(profile).stats  # (file, line, name) -> (cc, nc, tt, ct, callers)
    groups = {"CasADi Function calls (IDAS runs + SX evaluations)": 0.0,
              "constructing CasADi integrators": 0.0, "NumPy linear algebra": 0.0}
    total = 0.0
    for (file, _, name), (_, _, own, _, _) in stats.items():
        total += own
        if "Function_call" in name:
            groups["CasADi Function calls (IDAS runs + SX evaluations)"] += own
        elif name.endswith("casadi.integrator}") or "_casadi.integrator" in name:
            groups["constructing CasADi integrators"] += own
        elif "linalg" in file:
            groups["NumPy linear algebra"] += own
    groups["everything else (Python, conversions)"] = total - sum(groups.values())
    print("coarse split of the profiled time:")
    for name, seconds in groups.items():
        print(f"  {name:55s} {seconds:8.2f} s  {100 * seconds / total:5.1f} %")


if __name__ == "__main__":
    main()
