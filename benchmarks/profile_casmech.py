"""Where casmech's time goes: cProfile of one casmech.analyze run (plus its results table),
grouped, and IDAS's own counters and timers summed over every integrator the run made.

    python benchmarks/profile_casmech.py chain8 --rtol 1e-8 --t-end 10
    python benchmarks/profile_casmech.py chain32 --rtol 1e-8 --t-end 1 --mode compiled
    python benchmarks/profile_casmech.py chain8 --no-cprofile --repeats 3   # IDAS split only
    python benchmarks/profile_casmech.py chain8 --no-cprofile --idas max_order=3 \
        --idas linear_solver=csparse                        # IDAS options added to casmech's

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
from casmech_model import Runner, quaternion_matrix  # noqa: E402
from systems import OUTPUT_STEP, T_CHECK, T_END, error, make, points  # noqa: E402

from casmech.runtime import buffers  # noqa: E402
from reference import Planar  # noqa: E402

COUNTERS = ("nsteps", "nfevals", "nlinsetups", "nniters", "netfails", "nncfails")
TIMERS = ("t_wall_total", "t_wall_daeF", "t_wall_jacF")


class IntegratorSpy:
    """Wraps casadi.integrator as the DAE runtime (runtime.dae_integrators) sees it: records
    every integrator it makes (with record_time on), the time spent making them, and their
    options."""

    def __init__(self, module, extra: dict | None = None):
        self.module, self.original = module, module.ca.integrator
        self.made, self.creation = [], 0.0
        # integrators called through runtime.buffers.NamedCall keep their stats in its buffer,
        # which records no t_wall_total: the wall time of those calls stands for it
        self.calls, self.wall = {}, {}
        self.named_init, self.named_call = buffers.NamedCall.__init__, buffers.NamedCall.__call__
        self.extra = extra or {}

    def __enter__(self):
        def make_integrator(*args, **kwargs):
            args = list(args)
            options = dict(args[-1]) if isinstance(args[-1], dict) else {}
            args[-1] = scaled(options, self.extra) | {"record_time": True}
            start = time.perf_counter()
            made = self.original(*args, **kwargs)
            self.creation += time.perf_counter() - start
            self.made.append((made, args[2], options))
            return made

        def keep_call(named, function):
            self.calls[function.__hash__()] = named
            self.named_init(named, function)

        def timed_call(named, **inputs):
            start = time.perf_counter()
            try:
                return self.named_call(named, **inputs)
            finally:
                key = named.function.__hash__()
                self.wall[key] = self.wall.get(key, 0.0) + time.perf_counter() - start

        self.module.ca.integrator = make_integrator
        buffers.NamedCall.__init__, buffers.NamedCall.__call__ = keep_call, timed_call
        return self

    def __exit__(self, *_):
        self.module.ca.integrator = self.original
        buffers.NamedCall.__init__, buffers.NamedCall.__call__ = self.named_init, self.named_call

    def totals(self) -> dict:
        """Counters and timers summed over the integrators' last calls (each is called once)."""
        total = dict.fromkeys(COUNTERS + TIMERS, 0.0)
        for integrator, _, _ in self.made:
            named = self.calls.get(integrator.__hash__())
            stats = integrator.stats() if named is None else \
                named.stats() | {"t_wall_total": self.wall.get(integrator.__hash__(), 0.0)}
            for key in total:
                total[key] += stats.get(key, 0.0)
        total["integrators"] = len(self.made)
        total["creation"] = self.creation
        return total


def scaled(options: dict, extra: dict) -> dict:
    """casmech's options with `extra` added; the pseudo-options velocity_atol and
    algebraic_atol (factors) scale abstolv's velocity and algebraic entries (GGL, which sets
    abstolv: positions and velocities first, n_q = n_v in r-p)."""
    extra = dict(extra)
    factors = {key: extra.pop(key) for key in ("velocity_atol", "algebraic_atol") if key in extra}
    options = options | extra
    if factors and "abstolv" in options:
        atol = np.array(options["abstolv"])
        n_x = len(options["init_xdot"])
        atol[n_x // 2:n_x] *= factors.get("velocity_atol", 1.0)
        atol[n_x:] *= factors.get("algebraic_atol", 1.0)
        options["abstolv"] = list(atol)
    return options


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
    from casmech.runtime import dae_integrators, workspace

    atol = args.atol if args.atol is not None else args.rtol * 1e-2
    # each run makes (and times) its own integrator
    workspace.default(functions).drop("dae_integrators")
    with IntegratorSpy(dae_integrators, idas_options(args.idas)) as spy:
        start, cpu = time.perf_counter(), time.process_time()
        if profile:
            profile.enable()
        result = casmech.analyze(functions, "dynamics", t_end=args.t_end,
                                 output_step=OUTPUT_STEP, rtol=args.rtol, atol=atol,
                                 formulation=args.formulation)
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        casmech.results_table(functions, result)
        if profile:
            profile.disable()
        table = time.perf_counter() - start - wall
    totals = spy.totals() | {"wall": wall, "cpu": cpu, "table": table, "rows": len(result)}
    return totals, {"result": result, "spy": spy, "atol": atol}


def idas_options(pairs: list[str]) -> dict:
    """KEY=VALUE pairs as IDAS options (VALUE: a number, true/false, or a string)."""
    options = {}
    for pair in pairs:
        key, value = pair.split("=", 1)
        if value in ("true", "false"):
            options[key] = value == "true"
        else:
            try:
                options[key] = int(value) if value.lstrip("-").isdigit() else float(value)
            except ValueError:
                options[key] = value
    return options


def check_error(system, functions, result) -> float | None:
    """Error at T_CHECK against reference.py (cached in the temporary directory), or None
    when the run ends before it."""
    import tempfile

    import casmech

    names, values = casmech.results_table(functions, result)
    rows = np.flatnonzero(np.abs(values[:, 0] - T_CHECK) < 1e-9)
    if not len(rows):
        return None
    row = values[rows[0]]
    column = {name: k for k, name in enumerate(names)}
    cms = [[row[column[f"{bar.name}.{c}"]] for c in "xyz"] for bar in system.bars]
    rotations = [quaternion_matrix(np.array([row[column[f"{bar.name}.e{k}"]] for k in range(4)]))
                 for bar in system.bars]
    cache = os.path.join(tempfile.gettempdir(), f"casmech_reference_{system.name}.npy")
    if os.path.exists(cache):
        reference = np.load(cache)
    else:
        reference = Planar(system).solve()["points"]
        np.save(cache, reference)
    return error(points(system, np.array(cms), np.array(rotations)), reference)


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
    print(f"medians of {len(runs)} runs: wall {med['wall']:.3f} s, CPU {med['cpu']:.3f} s, "
          f"results_table "
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
    parser.add_argument("--formulation", default="rp", choices=("rp", "romega"),
                        help="the DAE's formulation (default rp)")
    parser.add_argument("--repeats", type=int, default=1, help="timed runs (medians)")
    parser.add_argument("--no-cprofile", action="store_true")
    parser.add_argument("--idas", action="append", default=[], metavar="KEY=VALUE",
                        help="an IDAS option added to casmech's (repeatable)")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="a constant of casmech.runtime.dynamics, for experiments")
    args = parser.parse_args(argv)

    from casmech.runtime import dynamics

    for name, value in idas_options(args.set).items():
        setattr(dynamics, name, value)
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
    print(f"error at t = {T_CHECK:g} s: "
          f"{check_error(runner.system, runner.functions, last['result'])}")
    options = last["spy"].made[-1][2]
    problem, state = _newton_system(runner.functions, last["result"], options)
    print_split(runs, linear_algebra(problem, options, *state))


def _newton_system(functions, result, options) -> tuple[dict, tuple]:
    """The DAE dictionary of the run's last integrator (GGL when it had step0, which only GGL
    sets) and (x, z, p) at the last output row (z: r-p accelerations or 0, multipliers 0, row
    scales 1; the Newton matrix's sparsity and conditioning hardly depend on them)."""
    from casmech.formulations import dae
    from casmech.runtime.dynamics import velocities

    name = result.metadata["formulation"]
    kind = "ggl" if "step0" in options else "projection"
    problem = dae.problem(dae.residual(functions.functions, name, kind))
    q = result.q[-1]
    x = np.concatenate([q, velocities(functions, name, q, result.q_dot[-1])])
    z = np.zeros(problem["z"].numel())
    if name == "rp":
        z[:len(q)] = result.q_ddot[-1]
    m = dae.sizes(functions.functions, name)[2]
    p = np.ones(problem["p"].numel())
    p[0], p[1:1 + m] = result.times[-1], 0.0
    return problem, (x, z, p)


if __name__ == "__main__":
    main()
