"""casmech check MODEL.yaml: validate; print diagnostics, DOF, rank, redundant constraints.

What `run` would refuse is an error here too (exit 1): an analysis type that is not available,
a kinematic analysis (kinematics, inverse_dynamics) of a mechanism with free degrees of
freedom (E501, as `run` words it), and constraints that cannot be met at t = 0 (E502: the
assembly every analysis starts with does not converge; each unmet row named at its joint's
line). A body's mesh file that is missing or that the animation's reader cannot read is an
error too (E410), though `run` never reads it, and so are drivers beyond plausible magnitudes
over the run and a tsda whose points coincide (schema/check_only.py), which `run` meets as a
results row that is not finite (exit 3).
"""

from __future__ import annotations

from pathlib import Path

from casmech import api
from casmech.cli.common import add_overrides, overrides
from casmech.errors import AnalysisError, BodyName, Diagnostic, ModelError
from casmech.schema import check_only

PRESCRIBED = ("kinematics", "inverse_dynamics")  # analyses that need 0 degrees of freedom


def add_arguments(parser) -> None:
    parser.add_argument("model", type=Path)
    add_overrides(parser)


def redundancy_warnings(report) -> list[Diagnostic]:
    return [Diagnostic("E500", row.joint, f"redundant constraint row: {row.label}", row.source,
                       hint="the row depends on earlier rows; its reaction is not unique "
                            "(casmech reports the minimum-norm one)", severity="warning")
            for row in report.redundant]


def analysis_errors(functions, report) -> list[Diagnostic]:
    """What `casmech run` would refuse in the model's `analysis:` block."""
    from casmech.api import ANALYSES
    from casmech.runtime.analyses import analysis_settings

    analysis = functions.ir.analysis
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
    try:  # its output grid's size, for the results table the model has
        analysis_settings(functions)
    except ModelError as error:
        return list(error.diagnostics)
    return []


HINT = ("a length, an angle or a driver's value at t = 0 that no pose reaches with the other "
        "joints (a distance longer than the links can span?); `casmech inspect` lists every "
        "row")


def assembly_errors(failure: AnalysisError) -> list[Diagnostic]:
    """E502 for each row (or joint) an assembly failure names."""
    from casmech.runtime.assembly import row_text

    context = failure.context
    rows = getattr(context, "rows", None)
    if rows:
        return [Diagnostic("E502", row.joint, f"{row_text(row)} cannot be met at t = 0 "
                           f"(residual {residual:.3e} where assembly's Newton iterations "
                           "stopped)", row.source, hint=HINT) for row, residual in rows]
    why = context.cause.split(";")[0]
    named = [Diagnostic("E502", name, f"{'body' if isinstance(name, BodyName) else 'joint'} "
                        f"'{name}' ({context.measure} {value:.3e}): {why}", source, hint=HINT)
             for name, source, value in context.joints]
    return named or [Diagnostic("E502", "joints", f"assembly failed: {why}", hint=HINT)]


def mesh_errors(model) -> list[Diagnostic]:
    """E410 for every mesh file the animation could not read (missing, unreadable, no
    triangles), as `casmech animate` words it."""
    meshes = [(index, n, item) for index, body in enumerate(model.bodies)
              for n, item in enumerate(body.geometry) if item["type"] == "mesh"]
    if not meshes:
        return []
    from casmech.io import animate

    folder = Path(model.file).parent
    problems = []
    for index, n, item in meshes:
        try:
            animate.mesh_file(folder / item["file"], item["scale"])
        except (OSError, ValueError) as error:
            problems.append(animate.mesh_problem(model, index, n, item, error))
    return problems


def run(args) -> int:
    from casmech.equations.checks import structure
    from casmech.runtime import assembly

    model = api.load(args.model, overrides(args.set))
    functions = api.compile(model, "interpreted")  # no build for a look at the structure
    failure = None
    try:
        q = assembly.assemble_positions(functions)
    except AnalysisError as error:
        failure, q = error, assembly.initial_guess(functions)
    report = structure(functions, 0.0, q)
    for diagnostic in redundancy_warnings(report):
        print(diagnostic.format())
    where = "assembled configuration" if failure is None else \
        "pose in the file (assembly failed)"
    print(f"{args.model}: {len(model.bodies)} bodies, {len(model.joints)} joints, "
          f"{len(model.forces)} forces; at the {where}:")
    print(report.summary())
    errors = [*(assembly_errors(failure) if failure is not None else ()),
              *analysis_errors(functions, report), *check_only.problems(model),
              *mesh_errors(model)]
    if errors:
        raise ModelError(errors)
    return 0
