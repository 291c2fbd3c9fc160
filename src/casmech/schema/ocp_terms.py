"""The `ocp:` block's cost terms, IPOPT options and initial-guess file (docs/optimal.md).

    objective: {integral: {EXPR: w}}   weight * integral EXPR^2 dt; EXPR an expression of t,
                                       the parameters and the readable state (the names an
                                       `outputs:` value reads, and the outputs)
    objective: {final: EXPR}           EXPR at the final time, added as written (Mayer)
    objective: {track: {COLUMN: {table: f.csv, column, interpolation, weight}}}
                                       weight * integral (COLUMN - table(t))^2 dt
    solver: {max_iter: 50, ...}        IPOPT options (core/ipopt_options.py)
    initial_guess: {file: dir/results.csv, controls: dir/controls.csv}

Expressions are checked as `outputs:` values are (E201 with a did-you-mean at the name, E200,
E203); a table as a motor's (schema/tables.py: E300 missing, E305 outside the model's folder,
E103 bad contents); an IPOPT option by the allow-list (E101, E102, E409); a guess file's path
as any file a model names (E305). Each finding is located at its key.
"""

from __future__ import annotations

import pathlib

from casmech.core.ipopt_options import IpoptOptions
from casmech.core.option_values import flat, with_values
from casmech.errors import did_you_mean, failed
from casmech.schema import events, files, outputs, spec
from casmech.schema.checker import Checker
from casmech.schema.loader import Path
from casmech.schema.motors import table


def _names(check: Checker, joints, forces, written) -> dict[str, float]:
    """What a cost expression may read, with a value for the finite check."""
    return {"t": 0.0, **outputs.readable(check, joints, forces),
            **{output.name: 0.0 for output in written or ()}}


def _function(check: Checker, path: Path, text: str, names: dict[str, float]):
    """The expression as a function of `names` (None: reported). An unknown name is E201 at
    its place with the hints of `outputs:` values (the joint's states, a body's columns)."""
    unknown = False
    for name, offset, _ in events.parsed_names(text):
        if name in names or name in check.parameters or name in check.broken:
            continue
        if "." in name:
            message, hint = events.misnamed(check, name, names, reactions=True)
        else:
            message, hint = f"unknown symbol '{name}'", did_you_mean(name, [*check.parameters,
                                                                             "t"])
        check.error("E201", path, message, source=check.inside(path, offset), hint=hint)
        unknown = True
    return None if unknown else check.function(path, text, names)


def _weight(check: Checker, path: Path, given) -> float | None:
    """A term's weight: a number at least 0 (E409: a negative weight makes the cost unbounded
    below)."""
    value = check.setting(path, given)
    if value is not None and not value >= 0:
        check.error("E409", path, "a cost weight must be at least 0", got=f"{value:g}",
                    hint="a term to maximise goes in `final:` with a minus sign")
        return None
    return value


def costs(check: Checker, given: spec.Objective, joints=(), forces=(), written=()):
    """(integral, final, track) of the objective, or None for a part that failed."""
    path: Path = ("ocp", "objective")
    names = _names(check, joints, forces, written)
    integral = {}
    for text, weight in given.integral.items():
        where = (*path, "integral", text)
        function = _function(check, where, text, names)
        value = _weight(check, where, weight)
        integral[text] = None if failed([function, value]) else (function, float(value))
    final = None if given.final is None else _function(check, (*path, "final"), given.final,
                                                       names)
    track = {}
    for column, item in given.track.items():
        where = (*path, "track", column)
        known = column in names and column != "t"
        if not known:
            message, hint = events.misnamed(check, column, names, reactions=True)
            check.error("E201", where, message, source=check.doc.locate_key(where), hint=hint)
        reference = table(check, where, spec.Table(table=item.table,
                                                    column=item.column or column,
                                                    interpolation=item.interpolation))
        weight = _weight(check, (*where, "weight"), item.weight)
        track[column] = (None if not known or failed([reference, weight])
                         else (reference, float(weight)))
    broken = failed([*integral.values(), *track.values()]) or (
        given.final is not None and final is None)
    return None if broken else (integral, final, track)


def solver(check: Checker, given) -> tuple | None:
    """The IPOPT options written, as (key, value) pairs, or None after an error."""
    if not given:
        return ()
    written = {".".join(key): value for key, value in flat(given)}
    _, problems = with_values(IpoptOptions(), written)
    for problem in problems:
        where = ("ocp", "solver", *problem.path)
        check.error(problem.code, where, f"{problem.message}: IPOPT option {problem.key}",
                    source=check.doc.locate_key(where), expected=problem.expected,
                    got=problem.got, hint=problem.hint)
    return None if problems else tuple(written.items())


def guess_file(check: Checker, given) -> tuple[str, ...] | None:
    """(results.csv, controls.csv) of an initial-guess file, () for none, None after an
    error. The files are read when the problem is solved (optimal/warm_start.py)."""
    if not isinstance(given, spec.GuessFile):
        return ()
    path: Path = ("ocp", "initial_guess")
    found = []
    for key, name in (("file", given.file), ("controls", given.controls)):
        if name is None:  # controls.csv beside the results
            found.append(str(pathlib.Path(found[0]).with_name("controls.csv")))
            continue
        try:
            found.append(str(files.resolve(check.doc.file, name, must_exist=False)))
        except files.NotAllowed as error:
            check.error("E305", (*path, key), f"initial guess file '{name}': {error.reason}",
                        hint=error.hint)
            return None
    return found[0], found[1]
