"""casmech optimize MODEL.yaml: solve the model's `ocp:` block (optimal control) or fit its
`estimate:` block (parameters to measurements); write the results into DIR."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from casmech import api
from casmech.cli.common import add_overrides, options, overrides
from casmech.core.ipopt_options import IpoptOptions
from casmech.core.option_values import with_values
from casmech.errors import UsageError
from casmech.io.csv import read_measurements, write_csv
from casmech.optimal import estimate as estimation
from casmech.optimal import ocp
from casmech.optimal.estimate_kinematics import estimate_kinematics
from casmech.optimal.shooting import INTEGRATORS
from casmech.schema import limits


def add_arguments(parser) -> None:
    parser.add_argument("model", type=Path)
    parser.add_argument("--out", type=Path, help="output directory (default MODEL_optimal/)")
    parser.add_argument("--transcription", choices=ocp.TRANSCRIPTIONS,
                        help="ocp: override the block's transcription")
    parser.add_argument("--intervals", type=int, help="ocp: override the number of intervals")
    parser.add_argument("--integrator", choices=INTEGRATORS,
                        help="ocp, joint coordinates: override the block's shooting integrator "
                             "(RK4 steps, or CVODES / IDAS with sensitivities)")
    parser.add_argument("--formulation", choices=ocp.FORMULATIONS,
                        help="ocp: override the block's formulation (joint coordinates where "
                             "they take the mechanism, or body coordinates)")
    parser.add_argument("--data", type=Path, help="estimate: measurements CSV (default: the "
                                                  "block's data, relative to the model)")
    parser.add_argument("--mode", choices=api.COMPILE_MODES, default="interpreted",
                        help="ocp collocation on interpreted SX functions (exact Hessian, the "
                             "default), on the compiled C functions (limited-memory Hessian) "
                             "or auto (as casmech run decides)")
    parser.add_argument("--verbose", action="store_true", help="print IPOPT's iterations")
    parser.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                        help="ocp: an IPOPT option, e.g. max_iter=50 or tol=1e-8, over the "
                             "block's solver: (repeatable; docs/optimal.md)")
    add_overrides(parser)


def _ipopt(texts: dict[str, str]) -> dict:
    """The IPOPT options of --option KEY=VALUE texts (the allow-list of
    casmech.core.ipopt_options)."""
    if not texts:
        return {}
    converted, problems = with_values(IpoptOptions(), texts, text=True)
    if problems:
        raise UsageError("; ".join(problem.line() for problem in problems))
    return {key: getattr(converted, key) for key in texts}


def _optimal_control(model, args, out: Path) -> None:
    problem, transcription = ocp.from_block(model.ocp)
    if args.intervals is not None:
        problems = limits.ocp_problems(None, args.intervals, problem.elements)
        if problems:
            raise UsageError(f"--intervals {args.intervals}: {next(iter(problems.values()))}")
        problem = ocp.OCP(**{**problem.__dict__, "intervals": args.intervals})
    problem = ocp.OCP(**{**problem.__dict__, "mode": args.mode,
                         "formulation": args.formulation or problem.formulation,
                         "integrator": args.integrator or problem.integrator,
                         "solver": {**problem.solver, **_ipopt(options(args.option))}})
    transcription = args.transcription or transcription
    start = time.perf_counter()
    guess = None
    joints = ocp.joints_of(model, problem) is not None
    if transcription == "shooting" and not joints:  # IDAS fails on a poor first guess
        guess = ocp.solve(model, problem, "collocation", verbose=args.verbose)
        print(f"initial guess: the collocation solution (objective {guess.objective:.10g})")
    solution = ocp.solve(model, problem, transcription, verbose=args.verbose, start=guess)
    error = ocp.replay_error(model, problem, solution)
    names, values = ocp.results_table(model, problem, solution)
    results = write_csv(out / "results.csv", names, values)
    controls = write_csv(out / "controls.csv", ["t", *(c.name for c in problem.controls)],
                         np.column_stack([solution.times[:len(solution.u)], solution.u]))
    coordinates = "joint coordinates" if joints else "body coordinates"
    print(f"ocp ({transcription}, {coordinates}, {problem.intervals} intervals): objective "
          f"{solution.objective:.10g}, IPOPT {solution.status} in {solution.iterations} "
          f"iterations, {time.perf_counter() - start:.3g} s")
    replayer = ("DOP853 from every node" if joints else "IDAS from the initial state")
    print(f"replay ({replayer}): max position error {error:.3g}")
    for name, value in zip(problem.parameters, solution.design, strict=True):
        print(f"decision parameter {name} = {value:.10g}")
    print(f"-> {results}, {controls}")


def _estimate(model, args, out: Path) -> None:
    block = model.estimate
    data = args.data or Path(model.file).parent / block.data
    times, measured = read_measurements(data, block.outputs)
    how = (estimate_kinematics if block.analysis == "kinematics" else estimation.estimate)
    fit = how(model, block.parameters, times, measured, block.weights, block.bounds,
              verbose=args.verbose)
    rows = np.column_stack([fit.initial, fit.values])
    path = write_csv(out / "estimate.csv", ["initial", "estimate"], rows)
    width = max(len(p) for p in fit.parameters)
    for name, before, after in zip(fit.parameters, fit.initial, fit.values, strict=True):
        print(f"{name:<{width}}  {before:.10g} -> {after:.10g}")
    rms = float(np.sqrt(np.mean(fit.residuals ** 2)))
    print(f"IPOPT {fit.status} in {fit.iterations} iterations; residual RMS {rms:.3g}")
    print(f"-> {path} (rows in the order {', '.join(fit.parameters)})")


def run(args) -> int:
    model = api.load(args.model, overrides(args.set))
    if model.ocp is None and model.estimate is None:
        raise UsageError(f"{args.model} has neither an 'ocp:' nor an 'estimate:' block; add one "
                         "(see README.md, 'Sensitivities, estimation, optimal control')")
    out = args.out or args.model.with_name(args.model.stem + "_optimal")
    if model.ocp is not None:
        _optimal_control(model, args, out)
    if model.estimate is not None:
        _estimate(model, args, out)
    return 0
