"""Loads on one moving body: a point force (`force`, at a point, default the centre of mass)
and a torque (`torque`): checks, lowering, laws, kernels (their YAML classes:
elements/forces/specs.py).

The vector `value` (three expressions of t that may read the state) is global, or in the body's
frame with `frame: body`. Generalized force: x_q^T F of the point x(q) (terms.point_force), or
2 G^T n_bar of the torque (terms.torque); no potential.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import casadi as ca
import numpy as np

from casmech.core import traced
from casmech.core.values import constant
from casmech.elements.forces.terms import Input, in_global, point_force, torque


# ---------------------------------------------------------------------------- resolution
def _load(check, path, given) -> dict[str, Any] | None:
    if not check.reference((*path, "body"), given.body, list(check.bodies), "moving body"):
        return None
    value = tuple(
        check.function((*path, "value", k), component, {"t": 0.0})
        for k, component in enumerate(given.value)
    )
    return dict(body=given.body, value=value, frame=given.frame)


def resolve_force(check, path, given) -> dict[str, Any] | None:
    fields = _load(check, path, given)
    if fields is None:
        return None
    body = check.bodies[given.body]
    default = None if body is None else body.position
    at = check.vector((*path, "at"), given.at, default) if default is not None else None
    fields["vectors"] = None if at is None else {"at": at}
    return fields


def resolve_torque(check, path, given) -> dict[str, Any] | None:
    return _load(check, path, given)


# ------------------------------------------------------------------------------ lowering
def lower(force, model, poses) -> dict[str, Any]:
    v, body = force.vectors, poses.index[force.body]
    points = {"s": poses.local(force.body, "P", traced.asarray(v["at"]))} if "at" in v else {}
    return dict(body_i=body, body_j=body, points=points, params={}, value=force.value,
                frame=force.frame)


# ------------------------------------------------------------------------------ the laws
def _value(force, x, read):
    """The force/torque vector in the global frame."""
    v = ca.vertcat(*[component.casadi(t=x.t, **read(component, x))
                     for component in force.value])
    return in_global(force.frame, x.frame(force.body_i).A, v)


def force_law(force, x, read) -> tuple:
    s_bar = constant(force.points.get("s", [0.0, 0.0, 0.0]))
    return point_force(x.frame(force.body_i), s_bar, x.q, _value(force, x, read)), 0.0


def torque_law(force, x, read) -> tuple:
    k = force.body_i
    generalized = ca.SX.zeros(x.q.numel(), 1)
    start = 3 * x.n_bodies + 4 * k
    generalized[start:start + 4] = torque(x.frame(k), x.p(k), _value(force, x, read))
    return generalized, 0.0


def with_inputs(force, u):
    """The vector's three components the inputs u."""
    return replace(force, value=tuple(Input(u[k]) for k in range(3)))


# ------------------------------------------------------------------------------- kernels
def force_data(force) -> np.ndarray:
    """The point of application (equations/force_kernels.py)."""
    return np.asarray(force.points.get("s", [0.0, 0.0, 0.0]), float)


def no_data(force) -> np.ndarray:
    return np.zeros(0)


def force_kernel(force_type, frame, motion, data, value, actuator, frame_name) -> tuple:
    """(generalized over body i's 7 coordinates, potential)."""
    x = motion[0]
    body = frame(0)
    return point_force(body, data[0:3], x[:7], in_global(frame_name, body.A, value)), ca.SX(0)


def torque_kernel(force_type, frame, motion, data, value, actuator, frame_name) -> tuple:
    x = motion[0]
    body = frame(0)
    vector = in_global(frame_name, body.A, value)
    return ca.vertcat(ca.SX(3, 1), torque(body, x[3:7], vector)), ca.SX(0)
