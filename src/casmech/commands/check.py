"""casmech check MODEL.yaml: validate; print diagnostics, DOF, rank, redundant constraints."""

from __future__ import annotations

from pathlib import Path

import casmech
from casmech.commands.common import add_overrides, overrides
from casmech.errors import Diagnostic


def add_arguments(parser) -> None:
    parser.add_argument("model", type=Path)
    add_overrides(parser)


def redundancy_warnings(report) -> list[Diagnostic]:
    return [Diagnostic("E500", row.joint, f"redundant constraint row: {row.label}", row.source,
                       hint="the row depends on earlier rows; its reaction is not unique "
                            "(casmech reports the minimum-norm one)", severity="warning")
            for row in report.redundant]


def run(args) -> int:
    model = casmech.load(args.model, overrides(args.set))
    functions = casmech.compile(model)
    report, assembled = casmech.check(functions)
    for diagnostic in redundancy_warnings(report):
        print(diagnostic.format())
    where = "assembled configuration" if assembled else "pose in the file (assembly failed)"
    print(f"{args.model}: {len(model.bodies)} bodies, {len(model.joints)} joints, "
          f"{len(model.forces)} forces; at the {where}:")
    print(report.summary())
    return 0
