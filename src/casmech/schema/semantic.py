"""ModelSpec -> ResolvedModel: cross-references, expression evaluation, physical sanity.

`resolve` collects every finding (parameters and names here, bodies in `bodies`, joints and forces
in `connections`) and returns them with the model, which is None if anything is wrong.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace

from casmech.core import traced
from casmech.core.option_values import SOLVER, flat, lookup, with_values
from casmech.core.options import OPTIONS
from casmech.errors import Diagnostic, failed
from casmech.schema import (
    events,
    files,
    initial,
    limits,
    motors,
    outputs,
    resolved,
    spec,
)
from casmech.schema.bodies import body, floors
from casmech.schema.checker import Checker
from casmech.schema.connections import joint
from casmech.schema.force_laws import StateChecker, force  # forces read the state
from casmech.schema.loader import Document, Path
from casmech.schema.modal import modal_settings


def analysis(check: Checker, given: spec.Analysis) -> resolved.Analysis | None:
    """The analysis settings, each within limits.analysis_problems (E409), with where each is
    written (the run checks its output grid's size: runtime.analyses.analysis_settings)."""
    path: Path = ("analysis",)
    keys = ("t_end", "output_step", "rtol", "atol")
    values = {key: check.setting((*path, key), getattr(given, key)) for key in keys}
    if failed(values.values()):
        return None
    # the output grid's size is a run's: a command line's --t-end may shorten it (the run checks
    # it with the settings it runs: runtime.analyses.analysis_settings, `casmech check`)
    problems = limits.analysis_problems(values, 0, grid=False)
    for key, problem in problems.items():
        check.error("E409", (*path, key), problem, got=f"{values[key]:g}",
                    hint=limits.HINTS.get(key))
    if given.method in limits.JOINT_METHODS and given.formulation in ("rp", "romega"):
        check.error("E409", (*path, "method"), f"{limits.joint_method(given.method)}; the rp "
                    f"and romega DAEs are integrated by {limits.BDF}", got=given.method,
                    hint="write formulation: joint (or auto), or remove method")
    options, written = analysis_options(check, given)
    source = check.doc.source_map.values.get(path)
    # where the grid, the tolerances and the formulation and method written are (a run's
    # located E409: runtime.analyses.analysis_settings)
    located = keys + tuple(key for key in ("formulation", "method")
                           if key in given.model_fields_set)
    return (
        None
        if problems or options is None
        else resolved.Analysis(given.type, **values, options=options, source=source,
                               written=written, sources=tuple(
                                   (key, check.doc.locate((*path, key))) for key in located))
    )


TOP_KEYS = ("formulation", "stabilization", "method")  # option keys beside `type` (at, inputs:
#                                                         schema.modal)


def analysis_options(check: Checker, given: spec.Analysis):
    """(the options of the analysis type, the option keys written) from the block's top keys
    and its `solver:` block, checked against the type's options (core.options): E101 for an
    unknown key (did you mean), E102 for a wrong type, E409 out of range; (None, ()) after an
    error."""
    kind = OPTIONS[given.type]
    written = {key: getattr(given, key) for key in TOP_KEYS if key in given.model_fields_set}
    for path, value in flat(given.solver or {}):
        written[".".join((SOLVER, *path))] = value
    mine = {key: value for key, value in written.items()
            if not key.startswith(SOLVER + ".") and lookup(kind, key) is not None}
    mine |= {key: value for key, value in written.items() if key.startswith(SOLVER + ".")}
    options, problems = with_values(kind(), mine)
    for problem in problems:
        where = ("analysis", *problem.path)
        hint = problem.hint
        if problem.code == "E101" and problem.path[-1] in spec.Analysis.model_fields:
            hint = f"{problem.path[-1]} is a key of analysis: itself, beside type"
        check.error(problem.code, where, f"{problem.message} for analysis type {given.type}",
                    source=check.doc.locate_key(where), expected=problem.expected,
                    got=problem.got, hint=hint)
    return (None, ()) if problems else (options, tuple(written.items()))


def _pairs(check: Checker, path: Path, given) -> dict[str, tuple[float, float]] | None:
    """{name: (low, high)} with low <= high (E409)."""
    pairs = {name: check.numbers((*path, name), pair) for name, pair in given.items()}
    pairs = {name: None if pair is None else traced.value(pair) for name, pair in pairs.items()}
    for name, pair in pairs.items():
        if pair is not None and pair[0] > pair[1]:
            check.error("E409", (*path, name), "bounds must be [low, high] with low <= high",
                        got=f"[{pair[0]:g}, {pair[1]:g}]")
            pairs[name] = None
    return None if failed(pairs.values()) else {k: (float(a), float(b))
                                                 for k, (a, b) in pairs.items()}


def estimation(check: Checker, given: spec.Estimate | None) -> resolved.Estimation | None:
    path: Path = ("estimate",)
    names = [check.reference((*path, "parameters", k), name, check.parameters, "parameter")
             for k, name in enumerate(given.parameters)]
    names += [check.reference((*path, "bounds", name), name, given.parameters,
                              "estimated parameter") for name in given.bounds]
    weights = {name: check.setting((*path, "weights", name), w)
               for name, w in given.weights.items()}
    bounds = _pairs(check, (*path, "bounds"), given.bounds)
    try:
        files.resolve(check.doc.file, given.data, must_exist=False)
    except files.NotAllowed as error:
        check.error("E305", (*path, "data"), f"data file '{given.data}': {error.reason}",
                    hint=error.hint)
        names.append(False)
    if not all(names) or failed([*weights.values(), bounds]):
        return None
    return resolved.Estimation(tuple(given.parameters), given.data, given.outputs, weights, bounds,
                               check.doc.source_map.values.get(path), given.analysis)


def _control(check: Checker, path: Path, given: spec.Control) -> resolved.ControlInput | None:
    known = check.reference((*path, "joint"), given.joint, check.joint_types, "joint")
    free = (-math.inf, math.inf)
    bounds = _pairs(check, path, {"bounds": given.bounds}) if given.bounds else {"bounds": free}
    if not known or bounds is None:
        return None
    return resolved.ControlInput(given.joint, given.type, *bounds["bounds"])


def optimal_control(check: Checker, given: spec.OptimalControl, joints=(), forces=(),
                    written=()) -> resolved.OptimalControl | None:
    path: Path = ("ocp",)
    horizon = check.setting((*path, "horizon"), given.horizon)
    if given.integrator != "rk4" and given.transcription != "shooting":
        check.error("E409", (*path, "integrator"), f"integrator {given.integrator} integrates "
                    "the intervals of multiple shooting", expected="transcription: shooting",
                    got=f"transcription: {given.transcription}",
                    hint="collocation has no integrator: remove the key or shoot")
    problems = limits.ocp_problems(horizon, given.intervals, given.elements)
    for key, problem in problems.items():
        check.error("E409", (*path, key), problem,
                    got=f"{horizon:g}" if key == "horizon" else str(getattr(given, key)))
    horizon = None if "horizon" in problems else horizon
    controls = [_control(check, (*path, "controls", k), c) for k, c in enumerate(given.controls)]
    objective = (*path, "objective")
    effort = check.setting((*objective, "effort"), given.objective.effort)
    costs = {name: (check.setting((*objective, "terminal", name, "weight"), cost.weight),
                    check.setting((*objective, "terminal", name, "target"), cost.target))
             for name, cost in given.objective.terminal.items()}
    terminal = {name: check.setting((*path, "terminal", name), value)
                for name, value in given.terminal.items()}
    bounds = _pairs(check, (*path, "path"), given.path)
    terminal_bounds = _pairs(check, (*path, "terminal_bounds"), given.terminal_bounds)
    design = _pairs(check, (*path, "parameters"), given.parameters)
    initial_bounds = _pairs(check, (*path, "initial_bounds"), given.initial_bounds)
    initial = {name: check.setting((*path, "initial", name), value)
               for name, value in given.initial.items()}
    weights = {name: check.setting((*objective, "weights", name), value)
               for name, value in given.objective.weights.items()}
    time_weight = check.setting((*objective, "time"), given.objective.time)
    free = _pairs(check, path, {"free_time": given.free_time}) if given.free_time else {}
    if free and not (limits.MIN_TIME <= free["free_time"][0]
                     and free["free_time"][1] <= limits.MAX_T_END):
        check.error("E409", (*path, "free_time"), "the final time's bounds must be between "
                    f"{limits.MIN_TIME:g} and {limits.MAX_T_END:g} s",
                    got="[{:g}, {:g}]".format(*free["free_time"]))
        free = None
    from casmech.schema import ocp_terms  # (on use: a model with an `ocp:` section)

    terms = ocp_terms.costs(check, given.objective, joints, forces, written)
    ipopt = ocp_terms.solver(check, given.solver)
    guess_file = ocp_terms.guess_file(check, given.initial_guess)
    values = [horizon, effort, bounds, terminal_bounds, design, initial_bounds, time_weight,
              free, terms, ipopt, guess_file, *controls, *terminal.values(), *weights.values(),
              *initial.values(),
              *(x for pair in costs.values() for x in pair)]
    if failed(values) or problems:
        return None
    integral, final, track = terms
    return resolved.OptimalControl(horizon, given.intervals, given.transcription, tuple(controls),
                                   effort, costs, terminal, bounds,
                                   check.doc.source_map.values.get(path),
                                   free.get("free_time"), time_weight,
                                   "simulation" if guess_file else given.initial_guess,
                                   max(given.elements, 1), given.stabilized,
                                   given.formulation, given.degree, given.scheme,
                                   given.piecewise, given.steps, given.path_grid, weights,
                                   terminal_bounds, design, given.initial_free, initial,
                                   initial_bounds, integral, final, track, ipopt,
                                   guess_file or None, given.integrator)


def resolve_model(check: Checker, given: spec.ModelSpec) -> resolved.ResolvedModel | None:
    check.parameter_values(given.parameters)
    if ("name",) in check.doc.source_map.values:  # written (an inline component's is its key)
        check.valid_name(("name",), given.name, check.doc.locate(("name",)), (), "")
    check.unique_names(given)
    gravity = check.numbers(("gravity",), given.gravity)
    bodies = []
    for index, item in enumerate(given.bodies):
        bodies.append(body(check, index, item))
        check.bodies.setdefault(item.name, bodies[-1])
    floors(check, bodies)
    for item in given.joints:  # couplings may name joints written after them
        if hasattr(item, "body_i"):
            check.joint_types.setdefault(item.name, item.type)
            check.joint_bodies.setdefault(item.name, (item.body_i, item.body_j))
    joints = [motors.joint(check, index, item, joint)  # tables and motors around joint
              for index, item in enumerate(given.joints)]
    forces = [force(check, index, item) for index, item in enumerate(given.forces)]
    initial.driven(check, joints)
    initial.velocities(check, given.bodies, joints)
    settings = modal_settings(check, given.analysis, analysis(check, given.analysis), joints,
                              forces)
    written = outputs.outputs(check, given.outputs, joints, forces)
    watched = events.events(check, given.events, joints, forces, written)
    if settings is not None and watched:
        settings = replace(settings, events=watched)
    estimate = estimation(check, given.estimate) if given.estimate is not None else None
    ocp = (optimal_control(check, given.ocp, joints, forces, written)
           if given.ocp is not None else None)
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
        estimate,
        ocp,
        outputs=written or (),
    )


def resolve(
    document: Document,
    model: spec.ModelSpec,
    overrides: Mapping[str, str] | None = None,
    symbols: Mapping | None = None,
) -> tuple[resolved.ResolvedModel | None, list[Diagnostic]]:
    """The resolved model (None if anything is wrong) and every finding; `symbols`: the
    parameters evaluated as traced numbers (Checker)."""
    check = StateChecker(document, overrides, symbols)
    return resolve_model(check, model), check.found
