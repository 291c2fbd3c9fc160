"""Where a repeated call of a closed loop's dynamics run on IDAS goes (the benchmark four-bar:
joint coordinates, its loop a DAE on IDAS, `method: bdf`: method auto runs this loop's
projected ODE on DOP853, benchmarks/loop_ode_costs.py), and what IDAS's own options would
change.

    PYTHONPATH=src python benchmarks/loop_dae_costs.py --mode compiled --rtols 1e-4 1e-6 1e-8
    PYTHONPATH=src python benchmarks/loop_dae_costs.py --options '{"max_order": 4}' \
        '{"step0": 10}' '{"lam": 0.01}' '{"linear_solver": "csparse"}'

Stages (CPU ms, median of --calls repeated calls of `casmech.analyze(functions,
"dynamics", t_end=1, output_step=0.01, rtol=r, atol=r/100, method="bdf")` in one process):
the IDAS call itself, the rest of the integrator call (its key, counters, finiteness checks),
the results rows, the
singular-pose check after the run (of it the mapped call: its compiled log-determinants, or Phi_q
at every row for NumPy's), and the Python elsewhere; with
IDAS's counters and its own split (CasADi's record_time: the residual, its Jacobian, the rest
is IDAS and its linear solver), and the error at t = 1 s against benchmarks/reference.py.

--options: IDAS from the run's own start, grid and options, each variant with one change
(a CasADi IDAS option, or step0 / lam / mu: the first step or the multipliers' Newton
tolerances multiplied by the number); the largest angle error over the grid against the same
IDAS at rtol 1e-12 and at t = 1 s, the IDAS call's CPU (median of --calls) and its counters.
"""

from __future__ import annotations

import argparse
import json
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

from reference import Planar  # noqa: E402

COUNTERS = ("nsteps", "nfevals", "nlinsetups", "netfails", "nncfails")


def _capture(seen: dict) -> None:
    """Record the IDAS problem, start, grid and options of the joint run's integrator."""
    from casmech.runtime import joint_dynamics

    kept, call = joint_dynamics._Integrator._kept, joint_dynamics._Integrator.__call__

    def kept_(self, plugin, key, problem, t0, times, options):
        seen.update(problem=problem, t0=t0, times=list(times), make_options=options,
                    mask=self.loops.mask)
        return kept(self, plugin, key, problem, t0, times, options)

    def call_(self, t0, times, x, z, trial=False):
        seen.update(x=x, z=z)
        return call(self, t0, times, x, z, trial)

    joint_dynamics._Integrator._kept, joint_dynamics._Integrator.__call__ = kept_, call_


def _options(seen: dict) -> dict:
    """The captured integrator's options (evaluated here, not in the timed calls)."""
    return dict(seen["make_options"]())


def _idas(seen: dict, options: dict):
    import casadi as ca

    problem = seen["problem"]  # the integrator's problem, or (since 6a116ae) what makes it
    problem = problem if isinstance(problem, (dict, ca.Function)) else problem()
    return ca.integrator("idas", "idas", problem, seen["t0"], seen["times"], options)


def time_idas(spent: dict, label: str) -> None:
    """Adds the CPU time of every call of the joint run's IDAS (runtime.buffers.NamedCall of
    the integrator named "joint") to spent[label]."""
    from casmech.runtime import buffers

    named = buffers.NamedCall.__call__

    def idas_call(self, **inputs):
        start = time.process_time()
        try:
            return named(self, **inputs)
        finally:
            if self.function.name() == "joint":
                spent[label] = spent.get(label, 0.0) + time.process_time() - start

    buffers.NamedCall.__call__ = idas_call


def _cpu(function, calls: int) -> float:
    times = []
    for _ in range(calls):
        start = time.process_time()
        function()
        times.append(time.process_time() - start)
    return statistics.median(times)


def stages(runner, rtols, calls: int, reference, seen: dict) -> None:
    import casmech
    from casmech.runtime import auto_formulation, joint_dynamics, singular_poses

    spent: dict[str, float] = {}
    _timed(joint_dynamics._Integrator, "__call__", "integrator", spent)
    _timed(getattr(joint_dynamics, "Recorder", None) or joint_dynamics._Recorder, "rows", "rows",
           spent)
    _timed(auto_formulation, "singular_poses", "singular poses", spent)
    def timed_call(find):
        """`find`'s mapped call with its CPU added to spent["mapped"]."""
        def found(*args):
            call = find(*args)
            if call is None:
                return None

            def mapped(*inputs):
                start = time.process_time()
                try:
                    return call(*inputs)
                finally:
                    spent["mapped"] = spent.get("mapped", 0.0) + time.process_time() - start
            return mapped
        return found

    # the check's mapped calls: the compiled log-determinant, or Phi_q for NumPy's (a src/
    # before the compiled one has only the latter)
    singular_poses._jacobians = timed_call(singular_poses._jacobians)
    if hasattr(singular_poses, "_compiled"):
        singular_poses._compiled = timed_call(singular_poses._compiled)
    time_idas(spent, "IDAS")
    print("| rtol | total | IDAS | integrator, rest | rows | singular poses (mapped call) | Python "
          "elsewhere | steps | residuals | Jacobians | IDAS: residual, Jacobian, rest | "
          "error at 1 s |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|")
    for rtol in rtols:
        def call(rtol=rtol):
            return casmech.analyze(runner.functions, "dynamics", t_end=1.0,
                                   output_step=systems.OUTPUT_STEP, rtol=rtol, atol=rtol / 100,
                                   method="bdf")

        out = runner.run({"rtol": rtol, "atol": rtol / 100}, t_end=1.0)
        rows = []
        for _ in range(calls):
            spent.clear()
            start = time.process_time()
            call()
            rows.append(dict(spent, total=time.process_time() - start))
        ms = {key: 1e3 * statistics.median(row.get(key, 0.0) for row in rows)
              for key in rows[0]}
        rest = ms["total"] - ms["integrator"] - ms["rows"] - ms["singular poses"]
        timed = _idas(seen, _options(seen) | {"record_time": True})
        for _ in range(5):  # record_time's figures are the last call's
            timed(x0=seen["x"], z0=seen["z"], p=seen["mask"])
        stats = timed.stats()
        split = [1e3 * stats[k] for k in ("t_proc_daeF", "t_proc_jacF", "t_proc_total")]
        counts = [stats[k] for k in ("nsteps", "nfevals", "nlinsetups")]
        error = systems.error(out["points"], reference)
        print(f"| {rtol:g} | {ms['total']:.2f} | {ms['IDAS']:.2f} | "
              f"{ms['integrator'] - ms['IDAS']:.2f} | {ms['rows']:.2f} | "
              f"{ms['singular poses']:.2f} ({ms['mapped']:.2f}) | {rest:.2f} | "
              f"{counts[0]} | {counts[1]} | {counts[2]} | {split[0]:.2f}, {split[1]:.2f}, "
              f"{split[2] - split[0] - split[1]:.2f} | {error:.1e} |")


def options(runner, rtols, calls: int, variants: list[dict], seen: dict) -> None:
    import numpy as np

    runner.run({"rtol": 1e-12, "atol": 1e-14}, t_end=1.0)
    exact = np.array(_idas(seen, _options(seen))(x0=seen["x"], z0=seen["z"],
                                                   p=seen["mask"])["xf"])
    n = len(seen["x"]) // 2  # the joint angles, then their rates
    print("| rtol | variant | largest angle error over the grid | at 1 s | IDAS CPU ms | "
          + " | ".join(COUNTERS) + " |")
    print("|---|---|---:|---:|---:|" + "---:|" * len(COUNTERS))
    for rtol in rtols:
        runner.run({"rtol": rtol, "atol": rtol / 100}, t_end=1.0)
        base = _options(seen)
        for variant in variants:
            chosen = dict(base)
            tolerances = list(base["abstolv"])
            for key, value in variant.items():
                if key == "step0":
                    chosen["step0"] = base["step0"] * value
                elif key in ("lam", "mu"):  # z = [lam, mu], each half of the algebraic states
                    m = (len(tolerances) - len(seen["x"])) // 2
                    first = len(seen["x"]) + (0 if key == "lam" else m)
                    tolerances[first:first + m] = [v * value for v in tolerances[first:first + m]]
                    chosen["abstolv"] = tolerances
                else:
                    chosen[key] = value
            try:
                integrator = _idas(seen, chosen)
                states = np.array(integrator(x0=seen["x"], z0=seen["z"], p=seen["mask"])["xf"])
            except RuntimeError as error:
                print(f"| {rtol:g} | {json.dumps(variant)} | failed: {str(error)[:60]} |")
                continue
            stats = integrator.stats()
            cpu = _cpu(lambda i=integrator: i(x0=seen["x"], z0=seen["z"], p=seen["mask"]),
                       calls)
            error = np.abs(states[:n] - exact[:n])
            print(f"| {rtol:g} | {json.dumps(variant) if variant else 'as run'} | "
                  f"{error.max():.2e} | {error[:, -1].max():.2e} | {1e3 * cpu:.3f} | "
                  + " | ".join(str(stats[k]) for k in COUNTERS) + " |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--system", default="four_bar")
    parser.add_argument("--mode", default="compiled", choices=("compiled", "interpreted"))
    parser.add_argument("--rtols", type=float, nargs="+", default=[1e-4, 1e-6, 1e-8])
    parser.add_argument("--calls", type=int, default=40)
    parser.add_argument("--options", nargs="*", metavar="JSON",
                        help="IDAS variants (default: the stages)")
    args = parser.parse_args()
    os.environ.setdefault("CASMECH_CACHE_DIR", str(Path(tempfile.gettempdir())
                                                   / "casmech_loop_dae_costs_cache"))
    seen: dict = {}
    _capture(seen)
    system = systems.make(args.system)
    runner = casmech_model.Runner(system, args.mode, method="bdf")
    if args.options is None:
        stages(runner, args.rtols, args.calls, Planar(system).solve()["points"], seen)
    else:
        options(runner, args.rtols, args.calls, [{}] + [json.loads(v) for v in args.options],
                seen)


if __name__ == "__main__":
    main()
