"""The dimension each YAML field takes (docs/format.md#units): a value written with units
(core/units.py) must have it; a value without units is SI and fits (core/dimensions.py).

`expected(data, path)` reads the field from its path (`("bodies", 0, "mass")`,
`("forces", 2, "stiffness")`: indices dropped) and, where the dimension depends on the
element, the element's `type` in the document's data (a spring's stiffness N/m, a rotational
spring's N m/rad; a joint stop's and a joint friction's by the coordinate they act on). Fields
not listed (directions, tolerances, weights, expressions of the state, a contact's normal law,
parameters) take any.
"""

from __future__ import annotations

from casmech.core import states
from casmech.core.units import (
    DAMPING,
    FORCE,
    LENGTH,
    MASS,
    NUMBER,
    RATE,
    ROTATIONAL_DAMPING,
    STIFFNESS,
    TIME,
    TORQUE,
    VELOCITY,
    Dimension,
    dimension,
)
from casmech.elements.coordinate_kinds import REGISTRY as KINDS
from casmech.elements.joint_types import REGISTRY

# (section, keys without indices) -> dimension
FIELDS: dict[tuple[str, tuple[str, ...]], Dimension] = {
    **{("bodies", key): value for key, value in {
        ("mass",): MASS, ("inertia",): dimension(mass=1, length=2), ("position",): LENGTH,
        ("velocity",): VELOCITY, ("angular_velocity",): RATE,
        ("geometry", "box"): LENGTH, ("geometry", "sphere"): LENGTH,
        ("geometry", "cylinder", "radius"): LENGTH, ("geometry", "cylinder", "length"): LENGTH,
        ("geometry", "offset"): LENGTH, ("geometry", "scale"): NUMBER}.items()},
    **{("joints", key): value for key, value in {
        ("at",): LENGTH, ("at_i",): LENGTH, ("at_j",): LENGTH, ("s_i",): LENGTH,
        ("s_j",): LENGTH, ("length",): LENGTH, ("reactions", "point"): LENGTH,
        ("initial", "angle_i"): NUMBER, ("initial", "angle_i_dot"): RATE,
        ("initial", "angle_j"): NUMBER, ("initial", "angle_j_dot"): RATE,
        ("initial", "angular_velocity"): RATE}.items()},
    ("gravity", ()): dimension(length=1, time=-2),
    **{("analysis", (key,)): TIME for key in ("t_end", "output_step", "at")},
    ("analysis", ("rtol",)): NUMBER,
    ("ocp", ("horizon",)): TIME, ("ocp", ("free_time",)): TIME,
    ("instances", ("position",)): LENGTH,
}
# (section, element type, keys) -> dimension, before FIELDS
TYPED: dict[tuple[str, str, tuple[str, ...]], Dimension] = {
    **{("forces", "tsda", (key,)): value for key, value in {
        "at_i": LENGTH, "at_j": LENGTH, "stiffness": STIFFNESS, "free_length": LENGTH,
        "damping": DAMPING, "actuator": FORCE}.items()},
    **{("forces", "rsda", (key,)): value for key, value in {
        "stiffness": TORQUE, "free_angle": NUMBER, "damping": ROTATIONAL_DAMPING,
        "actuator": TORQUE}.items()},
    ("forces", "force", ("at",)): LENGTH, ("forces", "force", ("value",)): FORCE,
    ("forces", "torque", ("value",)): TORQUE,
    **{("forces", "bushing", (key,)): value for key, value in {
        "at": LENGTH, "stiffness": STIFFNESS, "damping": DAMPING,
        "rotational_stiffness": TORQUE, "rotational_damping": ROTATIONAL_DAMPING,
        "preload_force": FORCE, "preload_torque": TORQUE}.items()},
    ("joints", "gear", ("ratio",)): NUMBER, ("joints", "rack_pinion", ("radius",)): LENGTH,
    ("joints", "screw", ("lead",)): LENGTH,
    **{("joints", kind, ("f",)): value for kind, value in {
        "dp1": NUMBER, "dp2": LENGTH, "d": dimension(length=2), "cd": LENGTH}.items()},
}
# keys of any contact element (casmech/elements/forces/contact_spec.py)
CONTACT: dict[tuple[str, ...], Dimension] = {
    ("radius",): LENGTH, ("radius_i",): LENGTH, ("radius_j",): LENGTH, ("center",): LENGTH,
    ("center_i",): LENGTH, ("center_j",): LENGTH, ("points",): LENGTH, ("ends",): LENGTH,
    ("plane", "at"): LENGTH, ("normal", "impact_velocity"): VELOCITY,
    ("friction", "static"): NUMBER, ("friction", "dynamic"): NUMBER,
    ("friction", "stiction_velocity"): VELOCITY, ("friction", "transition_velocity"): VELOCITY,
}


def coordinate_fields(kind) -> dict[tuple[str, ...], Dimension]:
    """A coordinate kind's keys in a joint (casmech.elements.coordinate_kinds): its driver,
    motor modes, `initial:` value and rate, its stop's keys and its friction's (the efforts
    and the damping of its coordinate)."""
    q = kind.quantity
    return {("driver", kind.name): q.value, ("initial", kind.name): q.value,
            ("initial", kind.rate): q.rate,
            **{("motor", mode): dim for mode, dim in zip(kind.motor, (q.value, q.rate, q.effort),
                                                         strict=True)},
            **{("limit", key): dim for key, dim in (("lower", q.value), ("upper", q.value),
                                                     ("stiffness", q.stiffness),
                                                     ("damping", q.damping))},
            **{("friction", key): dim for key, dim in (("coulomb", q.effort),
                                                        ("static", q.effort),
                                                        ("viscous", q.damping))}}


# a joint friction's load keys (the others are in the units of the coordinate's force)
FRICTION: dict[str, Dimension] = {"mu": NUMBER, "mu_static": NUMBER, "radius": LENGTH}


# a readable name's attribute (after its last dot: body and contact columns, joint states,
# reactions) -> its dimension, for the units of outputs (schema/outputs.py)
ANGULAR_ACCELERATION = dimension(time=-2)
READABLE: dict[str, Dimension] = {
    **dict.fromkeys(("x", "y", "z", "gap"), LENGTH),
    **dict.fromkeys(("vx", "vy", "vz"), VELOCITY),
    **dict.fromkeys(("ax", "ay", "az"), dimension(length=1, time=-2)),
    **dict.fromkeys(("wx", "wy", "wz", "angle_i_dot", "angle_j_dot"), RATE),
    **dict.fromkeys(("alphax", "alphay", "alphaz"), ANGULAR_ACCELERATION),
    **dict.fromkeys(("e0", "e1", "e2", "e3", "angle_i", "angle_j"), NUMBER),
    **dict.fromkeys(("fx", "fy", "fz", "normal_force", "friction_force"), FORCE),
    **dict.fromkeys(("tx", "ty", "tz", "torque"), TORQUE),
}


def readable(name: str) -> Dimension | None:
    """The dimension of a readable state name (`bar.vx`), by its attribute; None where the
    attribute does not tell it (a stop's gap: rad or m)."""
    if "." not in name:
        return None
    attribute = name.rpartition(".")[2]
    kind = KINDS.get(states.JOINT_COORDINATES.get(attribute, ""))
    if kind is not None:
        return kind.quantity.value if attribute == kind.name else kind.quantity.rate
    stopped = [kind.quantity.effort for kind in KINDS.values() if kind.column == attribute]
    return stopped[0] if stopped else READABLE.get(attribute)


def _type(data, path: tuple) -> str | None:
    """The `type` of the element a path is in (forces and joints), from the data."""
    try:
        kind = data[path[0]][path[1]].get("type")
    except (KeyError, IndexError, TypeError, AttributeError):
        return None
    return kind if isinstance(kind, str) else None


def expected(data, path) -> Dimension | None:
    """The dimension of the field at `path` (module docstring), or None for any."""
    if not isinstance(path, tuple) or not path or not isinstance(path[0], str):
        return None
    section = path[0]
    keys = tuple(part for part in path[1:] if isinstance(part, str))
    if keys[-2:] == ("axis_angle", "angle"):
        return NUMBER
    kind = _type(data, path) if section in ("forces", "joints") else None
    if (section, kind, keys) in TYPED:
        return TYPED[(section, kind, keys)]
    entry = REGISTRY.get(kind) if section == "joints" and kind else None
    if entry is not None and entry.limit and len(keys) == 2 and keys[0] in ("limit", "friction"):
        found = coordinate_fields(KINDS[entry.limit]).get(keys)
        return found if found is not None or keys[0] == "limit" else FRICTION.get(keys[1])
    if section == "joints" and len(keys) == 2 and keys[0] in ("driver", "motor", "initial"):
        found = [fields[keys] for fields in map(coordinate_fields, KINDS.values())
                 if keys in fields]
        if found:
            return found[0]
    if section == "forces" and keys in CONTACT:
        return CONTACT[keys]
    return FIELDS.get((section, keys))
