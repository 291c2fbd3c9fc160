"""The results contract's columns (docs/format.md): the body and joint columns, and the
quantity, SI unit and title of any results column from its name."""

from __future__ import annotations

from collections.abc import Sequence

from casmech.core.states import JOINT_QUANTITIES

# the body columns of the results contract (docs/format.md), in their order
BODY_COLUMNS = ("x", "y", "z", "e0", "e1", "e2", "e3", "vx", "vy", "vz", "wx", "wy", "wz",
                "ax", "ay", "az", "alphax", "alphay", "alphaz")
JOINT_COLUMNS = ("fx", "fy", "fz", "tx", "ty", "tz")  # each joint's reaction columns

# column suffix (after the last dot) or whole column name -> (quantity, unit, panel title)
QUANTITIES: dict[str, tuple[str, str, str]] = {
    **{s: ("position", "m", "CM position (global)") for s in ("x", "y", "z")},
    **{f"e{k}": ("Euler parameter", "-", "Euler parameters") for k in range(4)},
    **{f"v{s}": ("velocity", "m/s", "CM velocity (global)") for s in "xyz"},
    **{f"w{s}": ("angular velocity", "rad/s", "angular velocity (global)") for s in "xyz"},
    **{f"a{s}": ("acceleration", "m/s²", "CM acceleration (global)") for s in "xyz"},
    **{f"alpha{s}": ("angular acceleration", "rad/s²", "angular acceleration (global)")
       for s in "xyz"},
    **{f"f{s}": ("force", "N", "joint reaction force on body_j (global)") for s in "xyz"},
    **{f"t{s}": ("torque", "N m", "joint reaction torque about the joint point (global)")
       for s in "xyz"},
    "energy": ("energy", "J", "energy (kinetic + potential)"),
    # contact elements and joint stops (docs/forces.md#contact); a stop's gap is m or rad
    "normal_force": ("contact normal force", "N", "contact normal force"),
    "friction_force": ("contact friction force", "N", "contact friction force (magnitude)"),
    "gap": ("contact gap", "m", "contact gap (negative: overlap)"),
    "limit_gap": ("stop gap", "m or rad", "joint stop gap (negative: past the bound)"),
    "constraint_violation": ("constraint violation", "-", "constraint violation max |Φ|"),
    "t": ("time", "s", "time"),
    # joint states (casmech.core.states; a joint's columns map their suffix by JOINT_QUANTITIES;
    # a coordinate kind's value and rate, and its stop's `limit_<effort>`, are added by
    # casmech.elements.coordinate_kinds)
    "relative_e": ("relative Euler parameter", "-",
                   "relative rotations of spherical joints (Euler parameters, joint frame)"),
    "relative_w": ("relative angular velocity", "rad/s",
                   "relative angular velocities of spherical joints (joint frame)"),
}


def joint_quantity(column: str) -> tuple[str, str, str]:
    """(quantity, SI unit, panel title) of a joint state column `<joint>.<attribute>`."""
    return QUANTITIES[JOINT_QUANTITIES[column.rsplit(".", 1)[-1]]]


def quantity(column: str) -> tuple[str, str, str]:
    """(quantity, SI unit, panel title) of a results column, from its name."""
    key = column if column in QUANTITIES else column.rsplit(".", 1)[-1]
    return QUANTITIES.get(key, (key, "?", key))


def units(names: Sequence[str]) -> dict[str, str]:
    """The SI unit of every results column, from its name (as the plots label their axes)."""
    return {name: quantity(name)[1] for name in names}
