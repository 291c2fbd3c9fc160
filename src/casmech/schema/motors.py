"""Motors and data tables of a joint: resolved around `connections.joint`.

`joint(check, index, given, resolve)` takes the tables out of the joint's `driver:` values and
`f:` (so that the expression checks see a plain "0"), resolves the joint, then puts the table
functions back and adds the motor:

- position mode (`angle`, `displacement`): the joint's driver, exactly as `driver:` would;
- speed mode (`speed`, `velocity`): the driver angle(t) = integral of speed from 0 to t, formed
  in closed form (schema/antiderivative.py; tables: schema/tables.py), so the speed holds
  exactly; no closed form is a located error (E204);
- effort mode (`torque`, `force`): kept in `Joint.motor` as a function of t and the joint's
  coordinate and rate; equations/motors.py applies it as a generalized force pair.

Mismatched and unknown keys, two modes on one motion and a motion driven by both `driver:` and
`motor:` are E408/E101 with the keys the joint type allows.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from casmech.elements.coordinate_kinds import View
from casmech.elements.joint_types import COORDINATES, REGISTRY, coordinate_types, listed
from casmech.errors import did_you_mean, failed
from casmech.schema import files, spec
from casmech.schema.antiderivative import NoClosedForm, integral
from casmech.schema.checker import Checker
from casmech.schema.resolved import ScalarFunction
from casmech.schema.tables import TableError, is_table, table_function
from casmech.schema.tables import integral as table_integral

# position and speed mode -> the driver it becomes; speed modes; effort mode -> the variables
# its law reads (casmech.elements.coordinate_kinds: each kind's `motor`)
DRIVEN = View(lambda: {mode: name for name, c in COORDINATES.items() for mode in c.motor[:2]})
SPEEDS = View(lambda: {c.motor[1]: name for name, c in COORDINATES.items()})
EFFORT_VARIABLES = View(lambda: {c.motor[2]: c.attributes for c in COORDINATES.values()})
NO_CLOSED_FORM_HINT = ("write the motion itself as `{position}:` (position mode); a speed needs "
                       "polynomials, sin/cos/exp of a*t + b, step() or a table")


# ---------------------------------------------------------------------------------- tables
def table(check: Checker, where: tuple, given: spec.Table):
    """The function of t a `{table: ...}` value gives (None: reported). The file must be in
    the model's folder (schema/files.py)."""
    try:
        path = files.resolve(check.doc.file, given.table, must_exist=False)
    except files.NotAllowed as error:
        check.error("E305", (*where, "table"), f"table file '{given.table}': {error.reason}",
                    hint=error.hint)
        return None
    try:
        return table_function(path, given.column, given.interpolation, given.periodic,
                              check.doc.locate(where))
    except TableError as error:
        key_path = (*where, error.key)
        check.error(error.code, key_path, error.message, hint=error.hint, got=error.got)
        return None


def time_function(check: Checker, where: tuple, value: Any, at: dict):
    """A ScalarFunction of `at`'s variables (an expression or a table of t)."""
    if isinstance(value, spec.Table):
        return table(check, where, value)
    return check.function(where, value, at)


def _strip_tables(given) -> tuple[Any, dict[tuple, spec.Table]]:
    """The joint with every table value replaced by "0", and the tables by (key, ...)."""
    found: dict[tuple, spec.Table] = {}
    update: dict[str, Any] = {}
    if isinstance(getattr(given, "f", None), spec.Table):
        found[("f",)], update["f"] = given.f, "0"
    driver = getattr(given, "driver", None)
    if driver is not None:
        tables = {k: getattr(driver, k, None) for k in COORDINATES
                  if isinstance(getattr(driver, k, None), spec.Table)}
        found.update({("driver", k): v for k, v in tables.items()})
        if tables:
            update["driver"] = driver.model_copy(update=dict.fromkeys(tables, "0"))
    return (given.model_copy(update=update) if update else given), found


# ---------------------------------------------------------------------------------- motors
def motions(joint_type: str) -> tuple[tuple[str, ...], ...]:
    """The motor modes of each free motion of the joint type (position, speed, effort)."""
    entry = REGISTRY.get(joint_type)
    return tuple(COORDINATES[c].motor for c in entry.coordinates) if entry else ()


def _allowed(joint_type: str) -> str:
    return " | ".join(" | ".join(keys) for keys in motions(joint_type))


def _check_keys(check: Checker, path: tuple, given, motor: spec.Motor) -> list[str]:
    """The motor's keys if they fit the joint type, else report (E101, E408) and []."""
    keys = [k for k in type(motor).model_fields if getattr(motor, k) is not None]
    allowed = [k for motion in motions(given.type) for k in motion]
    hint = f"a {given.type} joint's motor takes {_allowed(given.type)}" if allowed else \
        f"motors act on {listed(coordinate_types())} joints"
    ok = True
    for key in motor.model_extra or {}:
        close = did_you_mean(key, allowed)
        check.error("E101", (*path, key), f"unknown motor key '{key}'",
                    source=check.doc.locate_key((*path, key)), hint=close or hint)
        ok = False
    for key in keys:
        if key not in allowed:
            check.error("E408", (*path, key), f"a {key} motor is not allowed on a {given.type} "
                        "joint", source=check.doc.locate_key((*path, key)), hint=hint)
            ok = False
    for motion in motions(given.type):
        modes = [k for k in keys if k in motion]
        if len(modes) > 1:
            check.error("E408", (*path, modes[1]), f"one mode per motion: {' and '.join(modes)} "
                        "both drive the same motion", hint=f"keep one of {' | '.join(motion)}")
            ok = False
    if not keys and ok:
        check.error("E408", path, "a motor needs a mode", hint=hint)
        ok = False
    return keys if ok else []


def _speed(check: Checker, where: tuple, value: Any, position: str):
    """The driver of a speed motor: the exact integral of the speed from t = 0."""
    function = time_function(check, where, value, {"t": 0.0})
    if function is None or is_table(function):
        return None if function is None else table_integral(function, 0.0)
    try:
        expr = integral(function.expr, function.constants)
    except NoClosedForm as error:
        offset, length = error.node.offset, getattr(error.node, "length", 0)
        part = function.text[offset:offset + length] if length else None
        check.error("E204", where, f"speed '{function.text}' has no closed-form integral: "
                    f"{error.why}", source=check.inside(where, offset), got=part,
                    hint=NO_CLOSED_FORM_HINT.format(position=position))
        return None
    return ScalarFunction(expr.text, expr, function.constants, ("t",), function.source)


def _mode(check: Checker, path: tuple, key: str, value: Any):
    where = (*path, key)
    if key in SPEEDS:
        return _speed(check, where, value, DRIVEN[key])
    if key in EFFORT_VARIABLES:
        at = dict.fromkeys(("t", *EFFORT_VARIABLES[key]), 0.0)
        return time_function(check, where, value, at)
    return time_function(check, where, value, {"t": 0.0})


def motor(check: Checker, path: tuple, given) -> dict[str, Any] | None:
    """{mode: function} of the joint's motor ({} without one; None: reported)."""
    given_motor = getattr(given, "motor", None)
    if given_motor is None:
        return {}
    where = (*path, "motor")
    keys = _check_keys(check, where, given, given_motor)
    driver = getattr(given, "driver", None)
    for key in keys:
        if key in DRIVEN and driver is not None and getattr(driver, DRIVEN[key], None) is not None:
            check.error("E408", (*where, key), f"the {DRIVEN[key]} of '{given.name}' is given by "
                        "both driver and motor", hint="keep one of them")
            return None
    modes = {key: _mode(check, where, key, getattr(given_motor, key)) for key in keys}
    return None if not keys or failed(modes.values()) else modes


# ----------------------------------------------------------------------------------- joint
def joint(check: Checker, index: int, given, resolve):
    """`resolve(check, index, given)` (connections.joint) with tables and the motor added."""
    path = ("joints", index)
    stripped, tables = _strip_tables(given)
    resolved = resolve(check, index, stripped)
    functions = {keys: table(check, (*path, *keys), value) for keys, value in tables.items()}
    modes = motor(check, path, given)
    if resolved is None or modes is None or failed(functions.values()):
        return None
    fields: dict[str, Any] = {}
    drivers = dict(resolved.drivers)
    for keys, function in functions.items():
        if keys == ("f",):
            fields["f"] = function
        else:
            drivers[keys[1]] = function
    drivers |= {DRIVEN[key]: function for key, function in modes.items() if key in DRIVEN}
    fields["drivers"] = {name: drivers[name] for name in COORDINATES if name in drivers}
    if any(key in DRIVEN for key in modes) and "driver" not in resolved.sources:
        sources = {**resolved.sources, "driver": check.doc.locate_key((*path, "motor"))}
        fields["sources"] = sources
    effort = {key: f for key, f in modes.items() if key in EFFORT_VARIABLES}
    return replace(resolved, **fields, motor=effort) if effort else replace(resolved, **fields)
