"""casmech run MODEL.yaml: run the model's analysis and write DIR/results.csv."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import casmech
from casmech.commands.common import add_overrides, overrides
from casmech.errors import AnalysisError
from casmech.output.csv import write_csv

HELP = "run the model's analysis; write results.csv"


def add_arguments(parser) -> None:
    parser.add_argument("model", type=Path)
    parser.add_argument("--out", type=Path, help="output directory (default MODEL_results/)")
    parser.add_argument("--t-end", type=float, help="end time [s]")
    parser.add_argument("--output-step", type=float, help="output interval [s]")
    parser.add_argument("--rtol", type=float,
                        help="relative tolerance of the integrator (dynamics)")
    parser.add_argument("--atol", type=float,
                        help="absolute tolerance of the integrator (dynamics)")
    parser.add_argument("--formulation", choices=["rp", "romega"],
                        help="equations of motion for dynamics (default: the model's, else rp)")
    parser.add_argument("--analysis", choices=sorted(casmech.api.ANALYSES), help="analysis type")
    add_overrides(parser)


def run(args) -> int:
    model = casmech.load(args.model, overrides(args.set))
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
