"""casmech command line: parse arguments, call the API, render diagnostics.

Exit codes (MODEL_FORMAT.md): 0 success, 1 model error, 2 usage error, 3 analysis failure.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import casmech
from casmech.errors import AnalysisError, CasmechError, Diagnostic, ModelError, Source, UsageError
from casmech.output.csv import write_csv


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="casmech", description=casmech.__doc__)
    parser.add_argument("--version", action="version", version=f"casmech {casmech.__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    check = commands.add_parser("check", help="validate a model; print DOF, rank, redundancy")
    check.add_argument("model", type=Path)
    check.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                       help="override a parameter (repeatable)")

    run = commands.add_parser("run", help="run the model's analysis; write results.csv")
    run.add_argument("model", type=Path)
    run.add_argument("--out", type=Path, help="output directory (default MODEL_results/)")
    run.add_argument("--t-end", type=float, help="end time [s]")
    run.add_argument("--output-step", type=float, help="output interval [s]")
    run.add_argument("--rtol", type=float, help="relative tolerance of the integrator (dynamics)")
    run.add_argument("--atol", type=float, help="absolute tolerance of the integrator (dynamics)")
    run.add_argument("--formulation", choices=["rp", "romega"],
                     help="equations of motion for dynamics (default: the model's, else rp)")
    run.add_argument("--analysis", choices=sorted(casmech.api.ANALYSES), help="analysis type")
    run.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                     help="override a parameter (repeatable)")
    return parser


def _overrides(pairs: list[str]) -> dict[str, str]:
    overrides = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise UsageError(f"--set expects NAME=VALUE, got '{pair}'")
        overrides[name.strip()] = value.strip()
    return overrides


def _redundancy_warnings(report) -> list[Diagnostic]:
    return [Diagnostic("E500", row.joint, f"redundant constraint row: {row.label}", row.source,
                       hint="the row depends on earlier rows; its reaction is not unique "
                            "(casmech reports the minimum-norm one)", severity="warning")
            for row in report.redundant]


def command_check(args) -> int:
    model = casmech.load(args.model, _overrides(args.set))
    functions = casmech.compile(model)
    report, assembled = casmech.check(functions)
    for diagnostic in _redundancy_warnings(report):
        print(diagnostic.format())
    where = "assembled configuration" if assembled else "pose in the file (assembly failed)"
    print(f"{args.model}: {len(model.bodies)} bodies, {len(model.joints)} joints, "
          f"{len(model.forces)} forces; at the {where}:")
    print(report.summary())
    return 0


def command_run(args) -> int:
    model = casmech.load(args.model, _overrides(args.set))
    out = args.out or args.model.with_name(args.model.stem + "_results")
    functions = casmech.compile(model)
    start = time.perf_counter()
    try:
        result = casmech.analyze(functions, args.analysis, args.t_end, args.output_step,
                                 rtol=args.rtol, atol=args.atol, formulation=args.formulation)
    except AnalysisError as error:
        if error.partial is not None and len(error.partial):
            path = write_csv(out / "results.csv", *casmech.results_table(functions, error.partial))
            print(f"kept {len(error.partial)} rows computed before the failure in {path}",
                  file=sys.stderr)
        raise
    path = write_csv(out / "results.csv", *casmech.results_table(functions, result))
    print(f"{result.metadata['analysis']}: {len(result)} rows, "
          f"{time.perf_counter() - start:.3g} s -> {path}")
    return 0


COMMANDS = {"check": command_check, "run": command_run}


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        return COMMANDS[args.command](args)
    except ModelError as error:
        print(error.format(), file=sys.stderr)
        return error.exit_code
    except CasmechError as error:
        print(f"casmech: {error}", file=sys.stderr)
        return error.exit_code
    except FileNotFoundError as error:
        print(f"casmech: {Source(str(error.filename), 1, 1)}: no such file", file=sys.stderr)
        return UsageError.exit_code


if __name__ == "__main__":
    sys.exit(main())
