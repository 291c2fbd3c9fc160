"""Where casmech's time goes: cProfile of one casmech.analyze run (plus its results table),
grouped, and IDAS's own counters and timers summed over every integrator the run made.

    python benchmarks/profile_casmech.py chain8 --rtol 1e-8 --t-end 10
    python benchmarks/profile_casmech.py chain32 --rtol 1e-8 --t-end 1 --mode compiled
    python benchmarks/profile_casmech.py chain8 --no-cprofile --repeats 3   # IDAS split only

Prints the top functions by own time and by cumulative time, a coarse split (CasADi Function
calls, integrator construction, NumPy linear algebra, the rest: Python), and IDAS's split of a
step: residual (daeF), Jacobian (jacF), and the rest of t_wall_total, which is the linear
algebra (factorizations at every linear setup, one solve per Newton iteration) plus IDAS's
own vector work; the factorization and solve are timed apart on the DAE's Jacobian at the
final state with the same linear-solver plugin, to split that rest."""

from __future__ import annotations

import os

# single-threaded BLAS, as run.py's workers (must precede the NumPy import)
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import argparse  # noqa: E402
import cProfile  # noqa: E402
import io  # noqa: E402
import pstats  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import casadi as ca  # noqa: E402
import numpy as np  # noqa: E402
from casmech_model import Runner  # noqa: E402
from systems import OUTPUT_STEP, T_END, make  # noqa: E402

COUNTERS = ("nsteps", "nfevals", "nlinsetups", "nniters", "netfails", "nncfails")
TIMERS = ("t_wall_total", "t_wall_daeF", "t_wall_jacF")


class IntegratorSpy:
    """Wraps casadi.integrator as the dynamics module sees it: records every integrator it
    makes (with record_time on), the time spent making them, and their options."""

    def __init__(self, module):
        self.module, self.original = module, module.ca.integrator
        self.made, self.creation = [], 0.0

    def __enter__(self):
        def make_integrator(*args, **kwargs):
            args = list(args)
            options = dict(args[-1]) if isinstance(args[-1], dict) else {}
            args[-1] = options | {"record_time": True}
            start = time.perf_counter()
            made = self.original(*args, **kwargs)
            self.creation += time.perf_counter() - start
            self.made.append((made, args[2], options))
            return made

        self.module.ca.integrator = make_integrator
        return self

    def __exit__(self, *_):
        self.module.ca.integrator = self.original

    def totals(self) -> dict:
        """Counters and timers summed over the integrators' last calls (each is called once)."""
        total = dict.fromkeys(COUNTERS + TIMERS, 0.0)
        for integrator, _, _ in self.made:
            stats = integrator.stats()
            for key in total:
                total[key] += stats.get(key, 0.0)
        total["integrators"] = len(self.made)
        total["creation"] = self.creation
        return total


def linear_algebra(problem: dict, options: dict, x: np.ndarray, z: np.ndarray, p: np.ndarray,
                   repeats: int = 300) -> tuple[float, float]:
    """(factorization, solve) seconds of the DAE's Newton matrix [F_x' cj + F_x, F_z] at a
    state, by the integrator's linear-solver plugin (default qr) through casadi.Linsol:
    nfact, and Linsol.solve (which factorizes again) minus nfact. Agrees with perf's split
    to ~1.5x (chain8: 81 us and 9 us here, ~83 us and ~6 us by perf)."""
    sym = type(problem["x"])
    xdot = sym.sym("xdot", problem["x"].sparsity())
    residual = ca.vertcat(problem["ode"] - xdot, problem["alg"])
    cj = sym.sym("cj")
    newton = (ca.jacobian(residual, ca.vertcat(problem["x"], problem["z"]))
              + cj * ca.jacobian(residual, ca.vertcat(xdot, sym(problem["z"].numel(), 1))))
    matrix = ca.Function("newton", [problem["x"], problem["z"], problem["p"], problem["t"], cj],
                         [newton])(x, z, p, 0.0, 1e3)
    solver = ca.Linsol("linsol", options.get("linear_solver", "qr"), matrix.sparsity(),
                       options.get("linear_solver_options", {}))
    solver.sfact(matrix)
    rhs = ca.DM(np.ones(matrix.size1()))
    seconds = []
    for call in (lambda: solver.nfact(matrix), lambda: solver.solve(matrix, rhs)):
        call()
        start = time.perf_counter()
        for _ in range(repeats):
            call()
        seconds.append((time.perf_counter() - start) / repeats)
    return seconds[0], seconds[1] - seconds[0]


def run_once(functions, args, profile=None) -> tuple[dict, dict]:
    import casmech
    from casmech.runtime import dynamics

    atol = args.atol if args.atol is not None else args.rtol * 1e-2
    with IntegratorSpy(dynamics) as spy:
        start = time.perf_counter()
        if profile:
            profile.enable()
        result = casmech.analyze(functions, "dynamics", t_end=args.t_end,
                                 output_step=OUTPUT_STEP, rtol=args.rtol, atol=atol)
        wall = time.perf_counter() - start
        casmech.results_table(functions, result)
        if profile:
            profile.disable()
        table = time.perf_counter() - start - wall
    totals = spy.totals() | {"wall": wall, "table": table, "rows": len(result)}
    return totals, {"result": result, "spy": spy, "atol": atol}


def print_cprofile(profile: cProfile.Profile, top: int) -> None:
    for key in ("tottime", "cumulative"):
        text = io.StringIO()
        pstats.Stats(profile, stream=text).sort_stats(key).print_stats(top)
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
    print("coarse split of the profiled time (analyze + results_table):")
    for name, seconds in groups.items():
        print(f"  {name:55s} {seconds:8.3f} s  {100 * seconds / total:5.1f} %")


def print_split(runs: list[dict], linalg: tuple[float, float]) -> None:
    """Medians over the runs of IDAS's counters and where a step's time goes."""
    med = {key: statistics.median(run[key] for run in runs) for key in runs[0]}
    steps = med["nsteps"]
    factor, solve = linalg
    t_linalg = factor * med["nlinsetups"] + solve * med["nniters"]
    t_idas = med["t_wall_total"]
    rest = t_idas - med["t_wall_daeF"] - med["t_wall_jacF"] - t_linalg
    print(f"medians of {len(runs)} runs: wall {med['wall']:.3f} s, results_table "
          f"{med['table']:.3f} s ({med['rows']:.0f} rows)")
    print("  IDAS: " + ", ".join(f"{key} {med[key]:.0f}" for key in COUNTERS)
          + f", integrators {med['integrators']:.0f}")
    lines = [("residual (daeF)", med["t_wall_daeF"]),
             ("Jacobian (jacF)", med["t_wall_jacF"]),
             (f"linear algebra (est.: {1e6 * factor:.1f} us/factorization, "
              f"{1e6 * solve:.1f} us/solve)", t_linalg),
             ("IDAS's own work (rest of t_wall_total)", rest),
             ("integrator creation", med["creation"]),
             ("Python outside IDAS (wall - IDAS - creation)",
              med["wall"] - t_idas - med["creation"])]
    for name, seconds in lines:
        print(f"  {name:62s} {seconds:8.3f} s  {100 * seconds / med['wall']:5.1f} %  "
              f"{1e6 * seconds / max(steps, 1):7.1f} us/step")
    print(f"  per IDAS step (t_wall_total / nsteps): {1e6 * t_idas / max(steps, 1):.1f} us; "
          f"wall per step {1e6 * med['wall'] / max(steps, 1):.1f} us")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("system")
    parser.add_argument("--rtol", type=float, default=1e-8)
    parser.add_argument("--atol", type=float, help="default rtol / 100")
    parser.add_argument("--t-end", type=float, default=T_END)
    parser.add_argument("--top", type=int, default=12)
    parser.add_argument("--mode", default="interpreted", choices=("interpreted", "compiled"))
    parser.add_argument("--repeats", type=int, default=1, help="timed runs (medians)")
    parser.add_argument("--no-cprofile", action="store_true")
    args = parser.parse_args(argv)

    runner = Runner(make(args.system), mode=args.mode)
    print(f"{args.system} ({args.mode}): rtol={args.rtol:g}, t_end={args.t_end:g}, "
          f"build {runner.build_time}")
    runs, last = [], None
    for k in range(args.repeats):
        profile = cProfile.Profile() if (k == 0 and not args.no_cprofile) else None
        totals, last = run_once(runner.functions, args, profile)
        runs.append(totals)
        if profile:
            print_cprofile(profile, args.top)
    print(f"metadata {last['result'].metadata}")
    options = last["spy"].made[-1][2]
    problem, state = _newton_system(runner.functions, last["result"], options)
    print_split(runs, linear_algebra(problem, options, *state))


def _newton_system(functions, result, options) -> tuple[dict, tuple]:
    """The DAE dictionary of the run's last integrator (GGL when it had abstolv, which only
    GGL sets) and (x, z, p) at the last output row (z: accelerations, multipliers 0; the
    Newton matrix's sparsity and conditioning hardly depend on them)."""
    from casmech.compiler import dae

    name = result.metadata["formulation"]
    kind = "ggl" if "abstolv" in options else "projection"
    problem = dae.problem(dae.residual(functions.functions, name, kind))
    x = np.concatenate([result.q[-1], result.q_dot[-1]])
    z = np.zeros(problem["z"].numel())
    z[:len(result.q_ddot[-1])] = result.q_ddot[-1]
    m = problem["p"].numel() - 1
    return problem, (x, z, np.concatenate([[result.times[-1]], np.zeros(m)]))


if __name__ == "__main__":
    main()
