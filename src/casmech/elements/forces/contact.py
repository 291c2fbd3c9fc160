"""Contact force elements: sphere-plane, sphere-sphere, point set-plane, capsule-plane.

Every element is a set of contact points (its shape: sphere_plane, ...); each has a signed
`gap` (distance between the surfaces, negative when they overlap), a unit `normal` n from body_i
towards body_j, and a point P in the middle of the overlap on the line through the sphere's
centre (or the point of the set) along n. On body_j at P acts F = F_n n + F_t, on body_i at P
the opposite:

    d = max(0, -gap), d_dot = -gap_dot (by AD)
    F_n = max(0, k d^n + c d^m d_dot) while d > 0, else 0        (contact_spec.py: k n c m)
    F_t = -mu(s) F_n v_t / s,  v_t = v_rel - (n . v_rel) n,  s = sqrt(|v_t|^2 + (eps v_s)^2)
    mu(s) = step(s, 0, 0, v_s, mu_s) + step(s, v_s, 0, v_t, mu_d - mu_s)   (Adams' STEP curve)

(the smooth law; `friction: {model: exact}` replaces F_t by exact Coulomb stick and slip at
each point: exact_friction, runtime/contact_friction.py)

v_rel = v_j(P) - v_i(P), the velocities of the two bodies' material points at P. The
generalized force is v_rel's Jacobian in q_dot transposed times F (virtual work: the virtual
displacement of a material point is its velocity's). With P on the normal line through the
centre, n . v_rel is exactly gap_dot, so the elastic part k d^n is -dV/dq of
V = k d^(n+1) / (n+1) (the potential energy column holds it: the energy is constant for
c = 0, mu = 0). The `eps` (EPS) keeps s > 0, so the friction's Jacobian is finite at zero slip.

Hunt-Crossley (Hunt, Crossley 1975, J. Appl. Mech. 42:440): F = k d^n (1 + alpha d_dot); its
restitution at approach speed v (no other force during the impact) solves
alpha e v + ln(1 - alpha e v) = -alpha v + ln(1 + alpha v), and contact_spec.py picks alpha
so that it is the file's `restitution` at its `impact_velocity` (docs/forces.md#contact).
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from casmech.core import euler, traced
from casmech.core.expressions import step
from casmech.core.records import record
from casmech.core.values import constant

EPS = 1e-6  # slip speed regularization, relative to the stiction velocity
GROUND = -1  # body index of ground (model/ir.GROUND_INDEX)
OUTPUTS = ("normal_force", "friction_force", "gap")  # results columns of a contact element


@record
class Point:
    """One contact point: gap, unit normal (body_i -> body_j), contact point P (global)."""

    gap: object
    normal: object
    at: object


def _point(x, k: int, s_bar):
    f = x.frame(k)
    return f.r + f.A @ constant(s_bar)


def _plane(force, x):
    """(point, unit normal) of the plane carried by body_i."""
    return _point(x, force.body_i, force.points["plane_at"]), \
        x.frame(force.body_i).A @ constant(force.axes["normal"])


def _sphere_on_plane(at, normal, center, radius) -> Point:
    gap = normal.T @ (center - at) - radius
    return Point(gap, normal, center - (radius + gap / 2) * normal)


def sphere_plane(force, x) -> list[Point]:
    at, normal = _plane(force, x)
    center = _point(x, force.body_j, force.points["center"])
    return [_sphere_on_plane(at, normal, center, force.params["radius"])]


def sphere_sphere(force, x) -> list[Point]:
    c_i = _point(x, force.body_i, force.points["center_i"])
    c_j = _point(x, force.body_j, force.points["center_j"])
    distance = ca.norm_2(c_j - c_i)
    normal = (c_j - c_i) / distance
    r_i = force.params["radius_i"]
    gap = distance - r_i - force.params["radius_j"]
    return [Point(gap, normal, c_i + (r_i + gap / 2) * normal)]


def _keys(force, prefix: str) -> list[str]:
    """"point0", "point1", ... (or "end0", "end1") in order."""
    found = [k for k in force.points if k.startswith(prefix) and k[len(prefix):].isdigit()]
    return sorted(found, key=lambda k: int(k[len(prefix):]))


def points_plane(force, x) -> list[Point]:
    at, normal = _plane(force, x)
    return [_sphere_on_plane(at, normal, _point(x, force.body_j, force.points[key]), 0.0)
            for key in _keys(force, "point")]


def capsule_plane(force, x) -> list[Point]:
    """A capsule on a plane: the spheres at its two ends (the deepest point of a segment's
    swept sphere is at an end, or both ends when it lies parallel to the plane)."""
    at, normal = _plane(force, x)
    return [_sphere_on_plane(at, normal, _point(x, force.body_j, force.points[key]),
                             force.params["radius"]) for key in _keys(force, "end")]


def _velocity(x, k: int, at):
    """Velocity of body k's material point at the global point `at` (ground: 0)."""
    if k == GROUND:
        return ca.SX.zeros(3, 1)
    omega = 2 * euler.e_matrix(x.p(k)) @ x.p(k, x.q_dot)  # global angular velocity
    return x.r(k, x.q_dot) + ca.cross(omega, at - x.r(k))


def normal_force(params, d, d_dot):
    """(F_n, elastic potential) of penetration d >= 0 and its rate."""
    k, n, c, m = (params[key] for key in ("stiffness", "exponent", "damping",
                                         "damping_exponent"))
    damping = c * d_dot * (d ** m if m != 0 else 1.0)
    force = ca.if_else(d > 0, ca.fmax(0, k * d ** n + damping), 0)
    return force, k * d ** (n + 1) / (n + 1)


def friction_coefficient(params, s):
    """mu(s): 0 at s = 0, mu_s at v_s, mu_d from v_t on (cubic steps between)."""
    mu_s, mu_d, v_s, v_t = (params[key] for key in ("mu_s", "mu_d", "v_s", "v_t"))
    return step(s, 0, 0, v_s, mu_s) + step(s, v_s, 0, v_t, mu_d - mu_s)


def tangential(force, x, point: Point) -> tuple:
    """(F_n, potential, v_t) of one contact point: its normal force and the tangential part
    of the relative velocity of the two bodies' material points at P."""
    d = ca.fmax(0, -point.gap)
    f_n, potential = normal_force(force.params, d, -x.rate(point.gap))
    v_rel = _velocity(x, force.body_j, point.at) - _velocity(x, force.body_i, point.at)
    return f_n, potential, v_rel - (point.normal.T @ v_rel) * point.normal


def exact_friction(force, k: int, f_n, v_t):
    """The exact law's friction at point k (`friction: {model: exact}`, the mode the runtime
    sets in params["modes"][k]: runtime/contact_friction.py): 0 while stuck (rows hold the
    point); else -mu_d F_n v_t / |v_t|, and along the slip direction u0 of a sliding mode (a
    3-tuple) where v_t . u0 <= 0 (a point just released, or one whose slip has reversed past
    the event that ends its segment); 0 while free (apart at the segment's start: the
    overshoot past the touch the runtime locates stays smooth); without a mode (the other
    analyses) the sliding law, 0 at v_t = 0."""
    modes = force.params.get("modes")
    mode = None if modes is None else modes[k]
    if mode in ("stuck", "free"):  # free: apart, until the event where it touches
        return ca.SX.zeros(3, 1)
    squared = v_t.T @ v_t
    if isinstance(mode, tuple):  # along u0 wherever the slip is not ahead of it: smooth
        u0 = ca.SX(ca.DM(mode))  # through the reversal of a straight slip, which the
        moving = (v_t.T @ u0 > 0) * (squared > 0)  # runtime's event locates
    else:
        u0, moving = ca.SX.zeros(3, 1), squared > 0
    speed = ca.sqrt(ca.if_else(moving, squared, 1))  # both branches and their AD finite
    return -force.params["mu_d"] * f_n * ca.if_else(moving, v_t / speed, u0)


def _point_law(force, x, point: Point, k: int) -> tuple:
    """(generalized force, potential, F_n, F_t) of contact point k."""
    f_n, potential, v_t = tangential(force, x, point)
    v_rel = _velocity(x, force.body_j, point.at) - _velocity(x, force.body_i, point.at)
    if force.params["mu_s"] == 0 and force.params["mu_d"] == 0:
        f_t = ca.SX.zeros(3, 1)
    elif force.params.get("exact"):
        f_t = exact_friction(force, k, f_n, v_t)
    else:
        s = ca.sqrt(v_t.T @ v_t + (EPS * force.params["v_s"]) ** 2)
        f_t = -friction_coefficient(force.params, s) * f_n / s * v_t
    total = f_n * point.normal + f_t
    return ca.jacobian(v_rel, x.q_dot).T @ total, potential, f_n, f_t


def _laws(force, x, shape) -> list[tuple]:
    return [(*_point_law(force, x, p, k), p.gap) for k, p in enumerate(shape(force, x))]


def generalized_force(force, x, read, shape) -> tuple:
    """(generalized force, potential) of a contact whose points `shape` gives (sphere_plane,
    ...): the law of its registry entry."""
    laws = _laws(force, x, shape)
    return sum(law[0] for law in laws), sum(law[1] for law in laws)


def outputs(force, x, shape) -> list:
    """The element's results columns (OUTPUTS): total normal force, magnitude of the total
    friction force, smallest gap."""
    laws = _laws(force, x, shape)
    friction = sum(law[3] for law in laws)
    gap = laws[0][4]
    for law in laws[1:]:
        gap = ca.fmin(gap, law[4])
    return [sum(law[2] for law in laws), ca.norm_2(friction), gap]


def pair_thickness(params) -> float:
    """R_i + R_j: how deep a sphere pair can overlap (runtime/contact_steps.py)."""
    return params["radius_i"] + params["radius_j"]


# ------------------------------------------------------------------------------- lowering
def lower(force, model, poses) -> dict[str, Any]:
    """resolved.Force (a contact type) -> the ForceIR fields."""
    v, i, j = force.vectors, force.body_i, force.body_j
    points, axes = {}, {}
    if "at" in v:
        points["plane_at"] = poses.local(i, "P", traced.asarray(v["at"]))
        axes["normal"] = poses.local(i, "axis", traced.asarray(v["normal"]))
    for key, body in (("center", j), ("center_i", i), ("center_j", j)):
        if key in v:
            points[key] = poses.local(body, "P", traced.asarray(v[key]))
    for key, prefix in (("points", "point"), ("ends", "end")):
        for n, p in enumerate(v.get(key, ())):
            points[f"{prefix}{n}"] = poses.local(j, "P", traced.asarray(p))
    return dict(body_i=poses.index[i], body_j=poses.index[j], points=points,
                params=dict(force.params), axes=axes)
