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
def friction(check: Checker, path: Path, given, entry=None) -> dict[str, float] | None:
    """A joint's `friction:` as coulomb, viscous, static (default: coulomb), mu, mu_static
    (default: mu) and radius (an angle's load arm; 0 when the coordinate is a displacement),
    each >= 0, the static limits at least the sliding ones."""
    values = {key: positive(check, (*path, key), check.number((*path, key), getattr(given, key)),
                            f"friction {key}", True)
              for key in ("coulomb", "viscous", "mu")}
    for key, default in (("static", "coulomb"), ("mu_static", "mu")):
        if getattr(given, key) is None:
            values[key] = values[default]
        else:
            values[key] = positive(check, (*path, key),
                                   check.number((*path, key), getattr(given, key)),
                                   f"friction {key}", True)
    if failed(values.values()):
        return None
    for key, sliding in (("static", "coulomb"), ("mu_static", "mu")):
        if values[key] < values[sliding]:
            what = "limit" if key == "static" else "coefficient"
            check.error("E103", (*path, key), f"the static friction {what} must be at least "
                        f"the sliding ({sliding}) one",
                        expected=f">= {values[sliding]:g}", got=f"{values[key]:g}",
                        hint=f"leave `{key}` out to use `{sliding}`")
            return None
    values["radius"] = _radius(check, path, given, entry, values)
    if failed([values["radius"]]):
        return None
    return {key: traced.scalar(value) for key, value in values.items()}


def _radius(check: Checker, path: Path, given, entry, values):
    """The load's arm: required (> 0) with a load part on an angle, refused on a displacement
    (whose load is the force itself); 0 when not used."""
    loaded = traced.value(values["mu_static"]) > 0
    angle = entry is None or entry.limit == "angle"
    if loaded and entry is not None and entry.name == "screw":  # its load: the thread's
        check.error("E103", (*path, "mu" if given.mu else "mu_static"), "a screw's friction "
                    "takes no load part: its thread's load is not modelled",
                    got=f"mu_static {traced.value(values['mu_static']):g}",
                    hint="give its friction as `coulomb` and `static` (N along the axis)")
        return None
    if given.radius is None:
        if loaded and angle:
            check.error("E100", path, "a revolute joint's friction with `mu` needs `radius`",
                        expected="radius: the arm (m) of the friction force, the friction "
                        "torque being radius * mu * |radial force|",
                        hint="add `radius:`, e.g. the bearing's radius")
            return None
        return 0.0
    if not angle:
        check.error("E103", (*path, "radius"), "`radius` applies to a revolute joint's "
                    "friction: along a displacement the load is the force itself",
                    got=f"radius on a {entry.name} joint", hint="remove `radius`")
        return None
    radius = positive(check, (*path, "radius"), check.number((*path, "radius"), given.radius),
                      "friction radius")
    return radius
