"""casmech sensitivity MODEL.yaml --parameter NAME --output COLUMN --at T: derivatives of results
columns with respect to parameters (geometry included) or initial velocities (IDAS forward or
adjoint; optimal/sensitivity.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from casmech import api
from casmech.cli.common import add_overrides, overrides
from casmech.io.csv import write_csv
from casmech.optimal.sensitivity import MODES, sensitivity


def add_arguments(parser) -> None:
    parser.add_argument("model", type=Path)
    parser.add_argument("--parameter", "--wrt", dest="parameter", action="append",
                        required=True, metavar="NAME",
                        help="a model parameter (masses, forces, drivers, and geometry: "
                             "lengths, joint points, axes, initial poses), or an initial "
                             "velocity <body>.vx..vz/.wx..wz (repeatable)")
    parser.add_argument("--output", action="append", required=True, metavar="COLUMN",
                        help="a results column, e.g. bar.x, pivot.fz, energy, or "
                             "integral(COLUMN), its integral from t = 0 (repeatable)")
    parser.add_argument("--at", action="append", required=True, type=float, metavar="T",
                        help="output time after t = 0 (repeatable)")
    parser.add_argument("--mode", choices=MODES, default="forward",
                        help="forward (one sweep per parameter) or adjoint (one backward sweep "
                             "per output); default forward")
    parser.add_argument("--rtol", type=float, default=1e-10, help="IDAS relative tolerance")
    parser.add_argument("--atol", type=float, default=1e-12, help="IDAS absolute tolerance")
    parser.add_argument("--csv", type=Path, help="also write the table to this CSV file")
    add_overrides(parser)


def table(result) -> tuple[list[str], np.ndarray]:
    """One row per (time, output): t, value, then d/d<parameter> for every parameter."""
    names = ["t", "value", *(f"d/d{p}" for p in result.parameters)]
    rows = [[t, result.values[k, i], *result.jacobian[k, i]]
            for k, t in enumerate(result.times) for i in range(len(result.outputs))]
    return names, np.array(rows)


def run(args) -> int:
    model = api.load(args.model, overrides(args.set))
    result = sensitivity(model, args.parameter, args.output, sorted(set(args.at)),
                         mode=args.mode, rtol=args.rtol, atol=args.atol)
    names, values = table(result)
    outputs = [o for _ in result.times for o in result.outputs]
    width = max(len(o) for o in outputs)
    print(f"{'output':<{width}}  " + "  ".join(f"{n:>16}" for n in names))
    for output, row in zip(outputs, values, strict=True):
        print(f"{output:<{width}}  " + "  ".join(f"{x:>16.9g}" for x in row))
    if args.csv:
        path = write_csv(args.csv, ["output_index", *names],
                         np.column_stack([np.tile(np.arange(len(result.outputs)),
                                                  len(result.times)), values]))
        print(f"-> {path} (output_index: 0 = {result.outputs[0]}, in --output order)")
    return 0
