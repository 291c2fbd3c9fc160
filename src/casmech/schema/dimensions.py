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

from casmech.core.units import FORCE, LENGTH, MASS, NUMBER, TIME, TORQUE, Dimension, dimension
from casmech.elements.joint_types import REGISTRY

VELOCITY, RATE = dimension(length=1, time=-1), dimension(time=-1)
STIFFNESS, DAMPING = dimension(mass=1, time=-2), dimension(mass=1, time=-1)
ROTATIONAL_DAMPING = dimension(mass=1, length=2, time=-1)

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
        ("driver", "angle"): NUMBER, ("driver", "displacement"): LENGTH,
        ("motor", "angle"): NUMBER, ("motor", "speed"): RATE, ("motor", "torque"): TORQUE,
        ("motor", "displacement"): LENGTH, ("motor", "velocity"): VELOCITY,
        ("motor", "force"): FORCE,
        ("initial", "angle"): NUMBER, ("initial", "angle_dot"): RATE,
        ("initial", "displacement"): LENGTH, ("initial", "displacement_dot"): VELOCITY,
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
# a joint stop's keys by the coordinate it stops (casmech.elements.joint_types `limit`)
LIMITS: dict[str, dict[str, Dimension]] = {
    "angle": {"lower": NUMBER, "upper": NUMBER, "stiffness": TORQUE,
              "damping": ROTATIONAL_DAMPING},
    "displacement": {"lower": LENGTH, "upper": LENGTH, "stiffness": STIFFNESS,
                     "damping": DAMPING},
}
# a joint friction's keys by the coordinate it acts on (the stop's: equations/friction.py)
FRICTION: dict[str, dict[str, Dimension]] = {
    "angle": {"coulomb": TORQUE, "static": TORQUE, "viscous": ROTATIONAL_DAMPING},
    "displacement": {"coulomb": FORCE, "static": FORCE, "viscous": DAMPING},
}
# a joint's keys whose dimension is by the coordinate its stop (`limit`) acts on
BY_COORDINATE = {"limit": LIMITS, "friction": FRICTION}


# a readable name's attribute (after its last dot: body and contact columns, joint states,
# reactions) -> its dimension, for the units of outputs (schema/outputs.py)
ANGULAR_ACCELERATION = dimension(time=-2)
READABLE: dict[str, Dimension] = {
    **dict.fromkeys(("x", "y", "z", "displacement", "gap"), LENGTH),
    **dict.fromkeys(("vx", "vy", "vz", "displacement_dot"), VELOCITY),
    **dict.fromkeys(("ax", "ay", "az"), dimension(length=1, time=-2)),
    **dict.fromkeys(("wx", "wy", "wz", "angle_dot", "angle_i_dot", "angle_j_dot"), RATE),
    **dict.fromkeys(("alphax", "alphay", "alphaz"), ANGULAR_ACCELERATION),
    **dict.fromkeys(("e0", "e1", "e2", "e3", "angle", "angle_i", "angle_j"), NUMBER),
    **dict.fromkeys(("fx", "fy", "fz", "normal_force", "friction_force", "limit_force"), FORCE),
    **dict.fromkeys(("tx", "ty", "tz", "limit_torque", "torque"), TORQUE),
}


def readable(name: str) -> Dimension | None:
    """The dimension of a readable state name (`bar.vx`), by its attribute; None where the
    attribute does not tell it (a stop's gap: rad or m)."""
    return READABLE.get(name.rpartition(".")[2]) if "." in name else None


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
    if entry is not None and entry.limit and len(keys) == 2 and keys[0] in BY_COORDINATE:
        return BY_COORDINATE[keys[0]][entry.limit].get(keys[1])
    if section == "forces" and keys in CONTACT:
        return CONTACT[keys]
    return FIELDS.get((section, keys))
