"""Contact elements' checks: their numbers, geometry and located errors (their YAML classes:
elements/forces/specs.py).

A contact entry of `forces:` resolves to a resolved.Force whose `vectors` hold its geometry,
GLOBAL at t = 0 like every point of the format (plane `at`, unit `normal`; sphere `center`,
`center_i`/`center_j`; `points` (k x 3); capsule `ends` (2 x 3)), and whose `params` hold the
radii and the normal law and friction in one form (elements/forces/contact.py):

    F_n = max(0, k d^n + c d^m d_dot) while d > 0      (d: penetration = -gap)
    hunt_crossley: n = exponent (1.5), m = n, c = k a(e) / v_in   (hunt_crossley_damping)
    linear:        n = 1, m = 0, c = damping

Sizes not written in the entry come from the body's `geometry` (the shapes the animation draws):
the first `sphere` item (radius, centre), the `box` item's 8 corners, the `cylinder` item's axis
segment and radius (a capsule). A body without that item and no explicit size is E410.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from casmech.core import euler, traced
from casmech.errors import failed

HERTZ = 1.5  # Hunt-Crossley's default exponent: Hertz's sphere on a flat


# -------------------------------------------------------------------------- checks
POSITIVE = ("stiffness", "impact_velocity")  # keys of the normal law that must be > 0


def positive(check, path, value, what: str, allow_zero: bool = False):
    if value is None:
        return None
    bad = value < 0 if allow_zero else value <= 0
    if bad:
        check.error("E103", path, f"{what} must be {'non-negative' if allow_zero else 'positive'}",
                    got=f"{value:g}")
        return None
    return value


def hunt_crossley_damping(e: float) -> float:
    """a = alpha v_in of F = k d^n (1 + alpha d_dot) whose restitution at impact speed v_in is
    exactly e: the root in (0, 1/e) of  a e + ln(1 - a e) = -a + ln(1 + a)  (the law integrated
    over an impact, m v dv / (1 + alpha v) = -k d^n dd; Hunt and Crossley's a = 3/2 (1 - e) is
    its first order in 1 - e). By bisection: f > 0 near 0, -> -inf at 1/e. A traced e (a
    symbolic parameter) gives a traced root (traced.root: Newton's steps on its expression)."""
    if e >= 1:
        return 0.0
    value = traced.value(e)
    low, high = 0.0, 1.0 / value
    for _ in range(200):
        a = 0.5 * (low + high)
        if a in (low, high):
            break
        f = a * value + math.log1p(-a * value) + a - math.log1p(a)
        low, high = (a, high) if f > 0 else (low, a)
    return traced.root(_restitution, 0.5 * (low + high), e)


def _restitution(a, e):
    """The residual whose root hunt_crossley_damping finds (SX)."""
    return a * e + ca.log1p(-a * e) + a - ca.log1p(a)


AXIS = {"x": 0, "y": 1, "z": 2}


def normal_law(check, path, given) -> dict[str, float] | None:
    """The normal law as params stiffness, exponent, damping, damping_exponent."""
    numbers = {key: check.number((*path, key), getattr(given, key))
               for key in ("stiffness", "exponent", "restitution", "impact_velocity", "damping")
               if getattr(given, key) is not None}
    for key in POSITIVE:  # both always present: stiffness required, impact_velocity default
        numbers[key] = positive(check, (*path, key), numbers[key], key.replace("_", " "))
    if given.law == "hunt_crossley":
        return _hunt_crossley(check, path, given, numbers)
    return _linear(check, path, given, numbers)


def _hunt_crossley(check, path, given, numbers) -> dict[str, float] | None:
    if given.damping is not None:
        check.error("E103", (*path, "damping"), "hunt_crossley takes restitution, not damping",
                    hint="law: linear has damping; Hunt-Crossley's damping follows from "
                    "restitution and impact_velocity")
        return None
    exponent = positive(check, (*path, "exponent"), numbers.get("exponent", HERTZ), "exponent")
    e = numbers.get("restitution", 1.0)
    if e is not None and not 0 < e <= 1:
        check.error("E103", (*path, "restitution"), "restitution must be in (0, 1]", got=f"{e:g}",
                    hint="the ratio of release to impact speed; 1: no loss")
        e = None
    k, v_in = numbers["stiffness"], numbers["impact_velocity"]
    if failed([exponent, e, k, v_in]):
        return None
    return {"stiffness": k, "exponent": exponent, "damping": k * hunt_crossley_damping(e) / v_in,
            "damping_exponent": exponent}


def _linear(check, path, given, numbers) -> dict[str, float] | None:
    for key in ("exponent", "restitution"):
        if getattr(given, key) is not None:
            check.error("E103", (*path, key), f"law: linear has no {key}",
                        hint="F = stiffness d + damping d_dot; exponent and restitution belong "
                        "to law: hunt_crossley")
            return None
    c = positive(check, (*path, "damping"), numbers.get("damping", 0.0), "damping", True)
    if failed([c, numbers["stiffness"]]):
        return None
    return {"stiffness": numbers["stiffness"], "exponent": 1.0, "damping": c,
            "damping_exponent": 0.0}


def friction(check, path, given) -> dict[str, float] | None:
    """mu_s, mu_d, v_s, v_t, exact (no friction: mu_s = mu_d = 0)."""
    if given is None:
        return {"mu_s": 0.0, "mu_d": 0.0, "v_s": 1.0, "v_t": 2.0, "exact": 0.0}
    if given.model == "exact":
        for key in ("stiction_velocity", "transition_velocity"):
            if key in given.model_fields_set:
                check.error("E103", (*path, key), f"model: exact has no {key}",
                            hint="exact Coulomb friction sticks at zero slip speed; the "
                            "stiction and transition velocities shape model: smooth's curve")
                return None
    mu_s = positive(check, (*path, "static"), check.number((*path, "static"), given.static),
                     "static friction coefficient", True)
    mu_d = mu_s if given.dynamic is None else positive(
        check, (*path, "dynamic"), check.number((*path, "dynamic"), given.dynamic),
        "dynamic friction coefficient", True)
    v_s = positive(check, (*path, "stiction_velocity"),
                    check.number((*path, "stiction_velocity"), given.stiction_velocity),
                    "stiction velocity")
    v_t = None if v_s is None else 2 * v_s
    if given.transition_velocity is not None:
        v_t = check.number((*path, "transition_velocity"), given.transition_velocity)
        if v_t is not None and v_s is not None and v_t <= v_s:
            check.error("E103", (*path, "transition_velocity"), "transition velocity must be "
                        "above the stiction velocity", got=f"{v_t:g} <= {v_s:g}")
            v_t = None
    if failed([mu_s, mu_d, v_s, v_t]):
        return None
    return {"mu_s": mu_s, "mu_d": mu_d, "v_s": v_s, "v_t": v_t,
            "exact": float(given.model == "exact")}


def plane(check, path, given) -> dict[str, np.ndarray | None]:
    return {"at": check.numbers((*path, "at"), given.at),
            "normal": check.direction((*path, "normal"), given.normal)}


# ---------------------------------------------------------------------------- body geometry
def _rotation(p) -> np.ndarray:
    """A(p) on numbers: body -> global."""
    return traced.numeric(euler.rotation, traced.asarray(p))


def _item(check, body: str, kind: str) -> dict[str, Any] | None:
    found = check.bodies.get(body)
    items = [] if found is None else [g for g in found.geometry if g["type"] == kind]
    return items[0] if items else None


def _global(check, body: str, item, local: np.ndarray) -> np.ndarray:
    """Points placed in a geometry item -> global at t = 0."""
    found = check.bodies[body]
    in_body = local @ _rotation(item["euler_parameters"]).T + item["offset"]
    return found.position + in_body @ _rotation(found.euler_parameters).T


def _no_shape(check, path, body: str, kind: str, keys: str) -> None:
    check.error("E410", path, f"body '{body}' has no {kind} geometry to take the contact's "
                f"{keys} from", hint=f"give {keys} here, or a {kind} item in the body's geometry")


def sphere(check, path, side: str, given, keys=("radius", "center")):
    """(radius, global centre) of the sphere on `given`'s body_<side>, from the entry's keys,
    else from the body's sphere geometry."""
    body = getattr(given, f"body_{side}")
    radius, center = (getattr(given, key) for key in keys)
    item = _item(check, body, "sphere")
    if (radius is None or center is None) and item is None:
        if check.bodies.get(body) is not None:
            _no_shape(check, (*path, f"body_{side}"), body, "sphere", " and ".join(keys))
        return None, None
    r = item["radius"] if radius is None else positive(
        check, (*path, keys[0]), check.number((*path, keys[0]), radius), "sphere radius")
    c = _global(check, body, item, np.zeros(3)) if center is None else check.numbers(
        (*path, keys[1]), center)
    return r, c


def box_corners(check, path, body: str, points) -> np.ndarray | None:
    """The points of a point set, global at t = 0: the entry's, else the box item's corners."""
    if points is not None:
        if not points:
            check.error("E103", (*path, "points"), "a point set needs at least one point")
            return None
        found = [check.numbers((*path, "points", k), p) for k, p in enumerate(points)]
        return None if failed(found) else np.array(found)
    item = _item(check, body, "box")
    if item is None:
        if check.bodies.get(body) is not None:
            _no_shape(check, (*path, "body_j"), body, "box", "points")
        return None
    half = traced.asarray(item["size"]) / 2
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
    return _global(check, body, item, signs * half)


def capsule(check, path, body: str, radius, ends):
    """(radius, 2 x 3 global end centres) from the entry, else the body's cylinder's axis."""
    item = _item(check, body, "cylinder")
    if (radius is None or ends is None) and item is None:
        if check.bodies.get(body) is not None:
            _no_shape(check, (*path, "body_j"), body, "cylinder", "radius and ends")
        return None, None
    r = item["radius"] if radius is None else positive(
        check, (*path, "radius"), check.number((*path, "radius"), radius), "capsule radius")
    if ends is None:
        half = np.zeros(3, object if traced.is_traced(item["length"]) else float)
        half[AXIS[item["axis"]]] = item["length"] / 2
        return r, _global(check, body, item, np.array([-half, half]))
    found = [check.numbers((*path, "ends", k), p) for k, p in enumerate(ends)]
    if not failed(found) and np.linalg.norm(found[1] - found[0]) < 1e-12:
        check.error("E410", (*path, "ends"), "a capsule's two ends coincide",
                    hint="a capsule of zero length is a sphere: type sphere_plane")
        return r, None
    return r, None if failed(found) else np.array(found)


# ----------------------------------------------------------------- the types' own keys
def sphere_plane(check, path, given) -> dict[str, Any] | None:
    radius, center = sphere(check, path, "j", given)
    return {"vectors": {**plane(check, (*path, "plane"), given.plane), "center": center},
            "params": {"radius": radius}}


def sphere_sphere(check, path, given) -> dict[str, Any] | None:
    r_i, c_i = sphere(check, path, "i", given, ("radius_i", "center_i"))
    r_j, c_j = sphere(check, path, "j", given, ("radius_j", "center_j"))
    return {"vectors": {"center_i": c_i, "center_j": c_j},
            "params": {"radius_i": r_i, "radius_j": r_j}}


def points_plane(check, path, given) -> dict[str, Any] | None:
    points = box_corners(check, path, given.body_j, given.points)
    return {"vectors": {**plane(check, (*path, "plane"), given.plane), "points": points},
            "params": {}}


def capsule_plane(check, path, given) -> dict[str, Any] | None:
    radius, ends = capsule(check, path, given.body_j, given.radius, given.ends)
    return {"vectors": {**plane(check, (*path, "plane"), given.plane), "ends": ends},
            "params": {"radius": radius}}


def resolve(check, path, given, shape) -> dict[str, Any] | None:
    """The fields of a contact's resolved.Force; `shape`: the type's own keys (sphere_plane,
    ...: {"vectors": ..., "params": ...})."""
    bodies_ok = check.two_bodies(path, given.body_i, given.body_j)
    law = normal_law(check, (*path, "normal"), given.normal)
    slip = friction(check, (*path, "friction"), given.friction)
    shape = shape(check, path, given) if bodies_ok else None
    if shape is None or failed([law, slip, *shape["vectors"].values(),
                                *shape["params"].values()]):
        return None
    return dict(body_i=given.body_i, body_j=given.body_j, vectors=shape["vectors"],
                params={**shape["params"], **law, **slip})


