"""The results columns of contact elements and joint stops, and joint limits: their numbers and
located errors (the contacts' own checks: casmech.elements.forces.contact_spec)."""

from __future__ import annotations

import numpy as np

from casmech.core import traced
from casmech.elements.force_types import outputs_of
from casmech.elements.forces.contact_spec import positive
from casmech.elements.joint_types import COORDINATES, REGISTRY
from casmech.errors import failed
from casmech.schema.checker import Checker
from casmech.schema.loader import Path


def output_names(joints, forces) -> list[str]:
    """The results columns of the force elements with outputs (their entry's `outputs` each, in
    file order), then the joint stops' (resolved joints and forces;
    equations.contact.output_names keeps the same order)."""
    names = [f"{f.name}.{o}" for f in forces if f is not None for o in outputs_of(f.type)]
    names += [f"{j.name}.{column}" for j in joints
              if j is not None and j.limit is not None
              for column in (limit_column(j.type), "limit_gap")]
    return names + [f"{j.name}.{column}" for j in joints
                    if j is not None and j.friction is not None for column in FRICTION_COLUMNS]


FRICTION_COLUMNS = ("friction", "friction_mode")  # equations/friction.py's outputs


def limit_column(joint_type: str) -> str:
    """A joint stop's force or torque column: by the coordinate it stops
    (casmech.elements.joint_types)."""
    return COORDINATES[REGISTRY[joint_type].limit].limit[1]


# ------------------------------------------------------------------------------ joint limits
def limit(check: Checker, path: Path, given) -> dict[str, float] | None:
    """A joint's `limit:` as lower, upper (+-inf when absent), stiffness, damping."""
    if given is None:
        return None
    bounds = {key: check.number((*path, key), getattr(given, key))
              for key in ("lower", "upper") if getattr(given, key) is not None}
    if not bounds:
        check.error("E100", path, "a limit needs lower, upper or both")
        return None
    k = positive(check, (*path, "stiffness"), check.number((*path, "stiffness"),
                                                            given.stiffness), "limit stiffness")
    c = positive(check, (*path, "damping"), check.number((*path, "damping"), given.damping),
                  "limit damping", True)
    lower, upper = bounds.get("lower", -np.inf), bounds.get("upper", np.inf)
    if failed([lower, upper, k, c]):
        return None
    if lower >= upper:
        check.error("E103", (*path, "upper"), "a limit's upper bound must be above its lower",
                    got=f"lower {lower:g}, upper {upper:g}")
        return None
    return {"lower": traced.scalar(lower), "upper": traced.scalar(upper), "stiffness": k,
            "damping": c}



# ---------------------------------------------------------------------------- joint friction
def friction(check: Checker, path: Path, given) -> dict[str, float] | None:
    """A joint's `friction:` as coulomb, viscous, static (default: coulomb), each >= 0, the
    static limit at least the sliding one."""
    values = {key: positive(check, (*path, key), check.number((*path, key), getattr(given, key)),
                            f"friction {key}", True)
              for key in ("coulomb", "viscous")}
    if given.static is None:
        values["static"] = values["coulomb"]
    else:
        values["static"] = positive(check, (*path, "static"),
                                    check.number((*path, "static"), given.static),
                                    "friction static", True)
    if failed(values.values()):
        return None
    if values["static"] < values["coulomb"]:
        check.error("E103", (*path, "static"), "the static friction limit must be at least "
                    "the sliding (coulomb) one", expected=f">= {values['coulomb']:g}",
                    got=f"{values['static']:g}", hint="leave `static` out to use `coulomb`")
        return None
    return {key: traced.scalar(value) for key, value in values.items()}
