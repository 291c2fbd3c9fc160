"""A closed loop's dynamics call by method: the joint DAE on IDAS (method auto) against the
loops' projected ODE on DOP853 (method dop853: formulations/loop_ode.py), on the benchmark
four-bar, by stage, with the error at t = 1 s.

    PYTHONPATH=src python benchmarks/loop_ode_costs.py --mode compiled \
        --rtols 1e-3 1e-4 1e-5 1e-6 1e-7 1e-8 --methods auto dop853

Stages (CPU ms, median of --calls repeated calls of `casmech.analyze(functions, "dynamics",
t_end=1, output_step=0.01, rtol=r, atol=r/100, method=m)` in one process): the integrator
call (of it the solver itself: IDAS's call, or the DOP853 call with its projections), the
results rows, the singular-pose check after the run, and the Python elsewhere; the accepted
steps; the error at t = 1 s against benchmarks/reference.py (the largest point error in m, as
benchmarks/run.py measures it). --rounds alternates the methods in that many passes (the
medians of the passes' medians) so that the machine's load hits each alike.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import casmech_model  # noqa: E402
import systems  # noqa: E402
from fixed_costs import _timed  # noqa: E402
from loop_dae_costs import time_idas  # noqa: E402

from reference import Planar  # noqa: E402


def _solver_time(spent: dict) -> None:
    """The solver's own call inside the integrator: IDAS through runtime.buffers.NamedCall,
    DOP853 through runtime.dop853.Dop853."""
    from casmech.runtime import dop853

    time_idas(spent, "solver")
    _timed(dop853.Dop853, "__call__", "solver", spent)


def measure(runner, methods, rtols, calls: int, rounds: int, reference) -> dict:
    import casmech
    from casmech.runtime import auto_formulation, joint_dynamics

    spent: dict[str, float] = {}
    _timed(joint_dynamics._Integrator, "__call__", "integrator", spent)
    _timed(joint_dynamics.Recorder, "rows", "rows", spent)
    _timed(auto_formulation, "singular_poses", "singular poses", spent)
    _solver_time(spent)
    passes: dict = {}
    for _ in range(rounds):
        for rtol in rtols:
            for method in methods:
                def call(rtol=rtol, method=method):
                    return casmech.analyze(runner.functions, "dynamics", t_end=1.0,
                                           output_step=systems.OUTPUT_STEP, rtol=rtol,
                                           atol=rtol / 100, method=method)

                result = call()  # the method's first call (its functions built) untimed
                rows = []
                for _ in range(calls):
                    spent.clear()
                    start = time.process_time()
                    call()
                    rows.append(dict(spent, total=time.process_time() - start))
                ms = {key: 1e3 * statistics.median(row.get(key, 0.0) for row in rows)
                      for key in rows[0]}
                passes.setdefault((rtol, method), []).append(
                    (ms, result.metadata.get("steps"), result.metadata.get("integrator")))
    out = {}
    for (rtol, method), found in passes.items():
        ms = {key: statistics.median(p[0].get(key, 0.0) for p in found) for key in found[0][0]}
        runner.method = {"method": method}
        error = systems.error(runner.run({"rtol": rtol, "atol": rtol / 100},
                                         t_end=1.0)["points"], reference)
        out[(rtol, method)] = ms, found[0][1], found[0][2], error
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--system", default="four_bar")
    parser.add_argument("--mode", default="compiled", choices=("compiled", "interpreted"))
    parser.add_argument("--rtols", type=float, nargs="+", default=[1e-3, 1e-5, 1e-7])
    parser.add_argument("--methods", nargs="+", default=["auto", "dop853"])
    parser.add_argument("--calls", type=int, default=30)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    os.environ.setdefault("CASMECH_CACHE_DIR", str(Path(tempfile.gettempdir())
                                                   / "casmech_loop_ode_costs_cache"))
    system = systems.make(args.system)
    runner = casmech_model.Runner(system, args.mode)
    out = measure(runner, args.methods, args.rtols, args.calls, args.rounds,
                  Planar(system).solve()["points"])
    print(f"{args.system}, {args.mode}, medians of {args.rounds} alternating passes of "
          f"{args.calls} calls (CPU ms)")
    print("| rtol | method (integrator) | total | integrator (solver) | rows | singular poses "
          "| Python elsewhere | steps | error at 1 s (m) |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for (rtol, method), (ms, steps, integrator, error) in out.items():
        rest = ms["total"] - ms["integrator"] - ms["rows"] - ms.get("singular poses", 0.0)
        print(f"| {rtol:g} | {method} ({integrator}) | {ms['total']:.2f} | "
              f"{ms['integrator']:.2f} ({ms.get('solver', 0.0):.2f}) | {ms['rows']:.2f} | "
              f"{ms.get('singular poses', 0.0):.2f} | {rest:.2f} | {steps} | {error:.1e} |")


if __name__ == "__main__":
    main()
