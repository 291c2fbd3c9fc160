"""The `outputs:` block: named values computed at every results row (docs/format.md#outputs).

An output's `value` is an expression of t, the parameters, the earlier outputs (by name) and
the readable state of the results table: every body column (`bar.x` .. `bar.alphaz`), every
joint state (`pivot.angle`, `cross.angle_i`, `ball.e0`: casmech.core.states), the contact and
stop columns (`floor.gap`, `pivot.limit_torque`) and the joints' reactions (`pivot.fx` ..
`pivot.tz`, in the frame and about the point the joint's `reactions:` names). Each output is a
results column named as the output, after the joint states (runtime/results.py). Its name is a
plain name (no dot), unique among outputs and parameters and none of t, pi, e, energy,
constraint_violation or a function's name (E301, E302, E303); an unknown name in `value` is
E201 at its place, with a did-you-mean hint. Its unit is the dimension of `value`
(core/dimensions.py) with the dimensions of what it reads (the states', reactions', time's,
parameters' written with units): a sum of different dimensions is E205; a value of no stated
dimension has no unit.
"""

from __future__ import annotations

from dataclasses import replace

from casmech.core import dimensions as core_dimensions
from casmech.core.columns import JOINT_COLUMNS
from casmech.core.units import NAMES, TIME, describe
from casmech.elements.joint_types import REGISTRY
from casmech.errors import did_you_mean
from casmech.schema import contact, dimensions, events, resolved, spec
from casmech.schema.checker import RESERVED, Checker
from casmech.schema.loader import Path, format_path

TABLE_NAMES = frozenset({"energy", "constraint_violation"})  # results columns without a dot
WHY = "t, pi, e, energy, constraint_violation and the function names are taken"


def readable(check: Checker, joints=(), forces=()) -> dict[str, float]:
    """Every state name an output may read, with its value at t = 0 as the file writes it
    (joint states, reactions and contact columns: 0), for the finite check of `value`."""
    names = events.state_names(check) | dict.fromkeys(contact.output_names(joints, forces), 0.0)
    couplings = {f"{joint}.{REGISTRY[kind].couples.column}": 0.0
                 for joint, kind in check.joint_types.items()
                 if kind in REGISTRY and REGISTRY[kind].couples}  # gear.torque, coupler.force
    return names | couplings | {f"{joint}.{column}": 0.0 for joint in check.joint_types
                                for column in JOINT_COLUMNS}


def si_unit(dimension) -> str:
    """The SI unit of a dimension ('m/s', 'N m'; '1' for a number)."""
    return NAMES[dimension][1] if dimension in NAMES else describe(dimension)


def _named(check: Checker, path: Path, name: str, first: dict[str, Path]) -> bool:
    """Whether the output's name is valid and new (reported when not)."""
    if not check.valid_name(path, name, check.doc.locate(path), RESERVED | TABLE_NAMES, WHY):
        return False
    if name in check.parameters or name in check.declared or name in check.broken:
        check.error("E301", path, f"output name '{name}' is a parameter's name",
                    hint="outputs and parameters share the names of expressions")
        return False
    if name in first:
        line = check.doc.locate(first[name]).line
        check.error("E301", path, f"duplicate output name '{name}' (first used by "
                    f"{format_path(first[name][:2])}, line {line})")
        return False
    return True


def _unknown(check: Checker, path: Path, given: spec.Output, names, earlier,
             broken: set[str]) -> set[str]:
    """Report (E201) every name `value` reads that is not readable; those names, and the
    earlier outputs it reads that failed (reported where they are)."""
    unknown: set[str] = set()
    for name, offset, _ in events.parsed_names(given.value):
        if name in broken:
            unknown.add(name)
        if name in names or name in earlier or name in unknown or name == "t":
            continue
        if "." in name:
            message, hint = events.misnamed(check, name, names, reactions=True)
        elif name in check.parameters or name in check.broken:
            continue
        else:
            message = f"unknown symbol '{name}'"
            hint = did_you_mean(name, [*check.parameters, *earlier, "t"])
        check.error("E201", path, message, source=check.inside(path, offset), hint=hint)
        unknown.add(name)
    return unknown


def outputs(check: Checker, given: tuple[spec.Output, ...], joints=(), forces=()
            ) -> tuple[resolved.Output, ...] | None:
    """The resolved outputs (None when any is wrong; every finding reported)."""
    if not given:
        return ()
    names = readable(check, joints, forces)
    first: dict[str, Path] = {}
    earlier: dict[str, float] = {}
    units_of: dict[str, object] = {}  # output -> its dimension (None: not stated)
    broken: set[str] = set()  # outputs that failed (not reported again where read)
    found = []
    for index, item in enumerate(given):
        name_path: Path = ("outputs", index, "name")
        named = _named(check, name_path, item.name, first)
        first.setdefault(item.name, name_path)
        path: Path = ("outputs", index, "value")
        unknown = _unknown(check, path, item, names, earlier, broken)
        used = {n: names.get(n, earlier.get(n, 0.0)) for n in events.read_names(item.value)
                if n in names or n in earlier}
        value = check.function(path, item.value, {"t": 0.0, **used,
                                                  **dict.fromkeys(unknown, 0.0)})
        if value is None or unknown or not named:
            found.append(None)
            broken.add(item.name)
            continue
        value = replace(value, variables=tuple(n for n in ("t", *used)
                                               if n in value.expr.symbols))
        dims = {**check.dimensions, **{n: dimensions.readable(n) for n in used}, **units_of,
                "t": TIME}
        try:
            dimension = core_dimensions.dimension(value.expr, dims)
        except core_dimensions.DimensionError as error:
            check.error(error.code, path, error.message, source=check.inside(path, error.offset))
            found.append(None)
            broken.add(item.name)
            continue
        found.append(resolved.Output(item.name, value, check.doc.locate(("outputs", index)),
                                     None if dimension is None else si_unit(dimension)))
        earlier[item.name] = 0.0
        units_of[item.name] = dimension
    return None if any(item is None for item in found) else tuple(found)
