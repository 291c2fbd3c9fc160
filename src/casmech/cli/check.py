"""casmech check MODEL.yaml: validate; print diagnostics, DOF, rank, redundant constraints.

What `run` would refuse is an error here too (exit 1): an analysis type that is not available,
and a kinematic analysis (kinematics, inverse_dynamics) of a mechanism with free degrees of
freedom (E501, as `run` words it).
"""

from __future__ import annotations

from pathlib import Path

from casmech import api
from casmech.cli.common import add_overrides, overrides
from casmech.errors import Diagnostic, ModelError

PRESCRIBED = ("kinematics", "inverse_dynamics")  # analyses that need 0 degrees of freedom


def add_arguments(parser) -> None:
    parser.add_argument("model", type=Path)
    add_overrides(parser)


def redundancy_warnings(report) -> list[Diagnostic]:
    return [Diagnostic("E500", row.joint, f"redundant constraint row: {row.label}", row.source,
                       hint="the row depends on earlier rows; its reaction is not unique "
                            "(casmech reports the minimum-norm one)", severity="warning")
            for row in report.redundant]


def analysis_errors(analysis, report) -> list[Diagnostic]:
    """What `casmech run` would refuse in the model's `analysis:` block."""
    from casmech.api import ANALYSES

    if analysis.type not in ANALYSES:
        return [Diagnostic("E409", "analysis.type", f"analysis type '{analysis.type}' is not "
                           "available yet", analysis.source, expected=" | ".join(ANALYSES),
                           got=analysis.type)]
    if analysis.type in PRESCRIBED and report.dof != 0:
        return [Diagnostic(
            "E501", "analysis.type",
            f"{analysis.type} needs a fully driven mechanism, but this one has {report.dof} "
            "degree(s) of freedom at the assembled configuration",
            analysis.source, expected="0 degrees of freedom", got=f"{report.dof}",
            hint="add drivers (`driver: {angle: ...}` on a revolute joint, `f:` on a basic "
                 "constraint) or run a dynamics analysis")]
    return []


def run(args) -> int:
    model = api.load(args.model, overrides(args.set))
    functions = api.compile(model)
    report, assembled = api.check(functions)
    for diagnostic in redundancy_warnings(report):
        print(diagnostic.format())
    where = "assembled configuration" if assembled else "pose in the file (assembly failed)"
    print(f"{args.model}: {len(model.bodies)} bodies, {len(model.joints)} joints, "
          f"{len(model.forces)} forces; at the {where}:")
    print(report.summary())
    errors = analysis_errors(functions.ir.analysis, report)
    if errors:
        raise ModelError(errors)
    return 0
