"""ModelSpec -> ResolvedModel: cross-references, expression evaluation, physical sanity.

`resolve` collects every finding (parameters and names here, bodies in `bodies`, joints and forces
in `connections`) and returns them with the model, which is None if anything is wrong.
"""

from __future__ import annotations

from collections.abc import Mapping

from casmech.errors import Diagnostic
from casmech.schema import resolved, spec
from casmech.schema.bodies import body
from casmech.schema.checker import Checker, failed
from casmech.schema.connections import force, joint
from casmech.schema.loader import Document, Path

ANALYSIS_RULES = {  # key -> problem with the settings `v`, or None
    "t_end": lambda v: "t_end must be positive" if v["t_end"] <= 0 else None,
    "output_step": lambda v: "output_step must be positive" if v["output_step"] <= 0 else None,
    "rtol": lambda v: "rtol must be positive" if v["rtol"] <= 0 else None,
    "atol": lambda v: "atol must be positive" if v["atol"] <= 0 else None,
}
STEP_RULE = "output_step must not exceed t_end"


def analysis(check: Checker, given: spec.Analysis) -> resolved.Analysis | None:
    path: Path = ("analysis",)
    keys = ("t_end", "output_step", "rtol", "atol")
    values = {key: check.number((*path, key), getattr(given, key)) for key in keys}
    if failed(values.values()):
        return None
    problems = {key: rule(values) for key, rule in ANALYSIS_RULES.items() if rule(values)}
    if not problems and values["output_step"] > values["t_end"]:
        problems["output_step"] = STEP_RULE
    for key, problem in problems.items():
        check.error("E409", (*path, key), problem, got=f"{values[key]:g}")
    options = {"formulation": given.formulation}
    source = check.doc.source_map.values.get(path)
    return (
        None
        if problems
        else resolved.Analysis(given.type, **values, options=options, source=source)
    )


def resolve_model(check: Checker, given: spec.ModelSpec) -> resolved.ResolvedModel | None:
    check.parameter_values(given.parameters)
    check.unique_names(given)
    gravity = check.numbers(("gravity",), given.gravity)
    bodies = []
    for index, item in enumerate(given.bodies):
        bodies.append(body(check, index, item))
        check.bodies.setdefault(item.name, bodies[-1])
    joints = [joint(check, index, item) for index, item in enumerate(given.joints)]
    forces = [force(check, index, item) for index, item in enumerate(given.forces)]
    settings = analysis(check, given.analysis)
    if check.found:
        return None
    parameters = dict(check.parameters)
    return resolved.ResolvedModel(
        given.name,
        given.description,
        check.doc.file,
        check.doc.text,
        parameters,
        gravity,
        tuple(bodies),
        tuple(joints),
        tuple(forces),
        settings,
    )


def resolve(
    document: Document,
    model: spec.ModelSpec,
    overrides: Mapping[str, str] | None = None,
) -> tuple[resolved.ResolvedModel | None, list[Diagnostic]]:
    """The resolved model (None if anything is wrong) and every finding."""
    check = Checker(document, overrides)
    return resolve_model(check, model), check.found
