"""Placing a resolved component in its parent: the instance frame (rotation R, origin d) applied
to everything the component wrote in GLOBAL-at-t = 0 terms, and every name prefixed with the
instance name (`leg1.` + `thigh`). Body-frame quantities (inertia, geometry, the a_i/s_i of
basic constraints on moving bodies, body-frame loads, bushing stiffnesses) are left alone;
on `ground` the a/s vectors of basic constraints are component-frame vectors and are placed.

    what it is              keys                                     placed as
    point                   position, at, at_i, at_j, a joint's      R x + d
                            reactions point
    direction               velocity, angular_velocity, axis,        R x
                            axis_i, axis_j, c, global value
    orientation             euler_parameters, bushing orientation   q_R * p
    relative rotation       a spherical joint's initial orientation q_R * p * conj(q_R)
                            (and its initial angular_velocity: R x)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields, is_dataclass, replace

import numpy as np

from casmech.core import traced
from casmech.core.expressions import Binary, Expr, Name, Number
from casmech.core.records import record
from casmech.schema import resolved
from casmech.schema.resolved import GROUND

POINT = frozenset({"at", "at_i", "at_j", "center", "center_i", "center_j"})  # + contact centres
DIRECTION = frozenset({"axis", "axis_i", "axis_j", "c", "normal"})  # + a contact plane's normal
POINT_SETS = frozenset({"points", "ends"})  # contact point sets (k x 3): each row a point
ORIENTATION = frozenset({"orientation"})
GROUND_SIDE = {"a_i": ("body_i", DIRECTION), "s_i": ("body_i", POINT),
               "a_j": ("body_j", DIRECTION), "s_j": ("body_j", POINT)}


def quaternion_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Euler parameters of A(a) A(b) (Hamilton product)."""
    a0, av, b0, bv = a[0], np.asarray(a[1:]), b[0], np.asarray(b[1:])
    return np.concatenate([[a0 * b0 - av @ bv], a0 * bv + b0 * av + np.cross(av, bv)])


@record
class Frame:
    """An instance's frame: origin and orientation in its parent's frame."""

    origin: np.ndarray
    euler_parameters: np.ndarray
    rotation: np.ndarray

    @property
    def rotated(self) -> bool:
        return not np.array_equal(self.euler_parameters, [1.0, 0.0, 0.0, 0.0])

    def point(self, x: np.ndarray) -> np.ndarray:
        return self.direction(x) + self.origin

    def direction(self, x: np.ndarray) -> np.ndarray:
        return self.rotation @ x if self.rotated else traced.asarray(x)

    def orientation(self, p: np.ndarray) -> np.ndarray:
        return quaternion_product(self.euler_parameters, p) if self.rotated else p

    def vector(self, kind: frozenset, x: np.ndarray) -> np.ndarray:
        return (self.point if kind is POINT else self.orientation if kind is ORIENTATION
                else self.direction)(x)


class Names:
    """Prefixing of member names (ground stays ground) and of dotted state names."""

    def __init__(self, prefix: str, members: set[str]):
        self.prefix = prefix
        self.members = members

    def __call__(self, name: str | None) -> str | None:
        return name if name is None or name == GROUND else f"{self.prefix}.{name}"

    def state(self, name: str) -> str:
        owner = name.rsplit(".", 1)[0]
        return f"{self.prefix}.{name}" if "." in name and owner in self.members else name

    def expression(self, node):
        """The expression tree with its dotted state names prefixed."""
        if isinstance(node, Name):
            return replace(node, name=self.state(node.name))
        if not is_dataclass(node):
            return node
        changes = {f.name: self.expression(getattr(node, f.name)) for f in fields(node)
                   if is_dataclass(getattr(node, f.name)) or isinstance(getattr(node, f.name),
                                                                         tuple)}
        changes = {k: tuple(map(self.expression, v)) if isinstance(v, tuple) else v
                   for k, v in changes.items()}
        return replace(node, **changes) if changes else node

    def function(self, function: resolved.ScalarFunction | None):
        if function is None or not any("." in v for v in function.variables):
            return function
        expr = Expr(function.expr.text, self.expression(function.expr.root))
        return replace(function, expr=expr, variables=tuple(map(self.state, function.variables)))


def rotate_functions(frame: Frame, functions):
    """(f_x, f_y, f_z) -> R (f_x, f_y, f_z) as three expressions of the same variables. An
    entry of R that depends on symbolic parameters (a traced number) enters as a constant of
    the function, named `R[row,column]`, so that it stays model data."""
    if not frame.rotated:
        return functions
    rotated = []
    for r, row in enumerate(frame.rotation):
        terms = [(traced.scalar(c), k, f) for k, (c, f) in enumerate(zip(row, functions,
                                                                         strict=True))
                 if c != 0.0]
        root, pieces, constants = Number(0.0, 0, 1), [], {}
        for n, (c, k, f) in enumerate(terms):
            factor = Number(c, 0, 1)
            if isinstance(c, traced.Traced):
                factor = Name(f"R[{r},{k}]", 0, 1)
                constants[factor.name] = c
            node = Binary("*", factor, f.expr.root, 0)
            root = node if n == 0 else Binary("+", root, node, 0)
            pieces.append(f"{factor.name if isinstance(factor, Name) else repr(c)}*({f.text})")
        text = " + ".join(pieces) or "0"
        with_constants = {**functions[0].constants, **constants} if constants else \
            functions[0].constants
        rotated.append(replace(functions[0], text=text, expr=Expr(text, root),
                               constants=with_constants))
    return tuple(rotated)


def body(frame: Frame, names: Names, given: resolved.Body) -> resolved.Body:
    return replace(given, name=names(given.name), position=frame.point(given.position),
                   euler_parameters=frame.orientation(given.euler_parameters),
                   velocity=frame.direction(given.velocity),
                   angular_velocity=frame.direction(given.angular_velocity))


def _vectors(frame: Frame, item, vectors: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    placed = {}
    for key, value in vectors.items():
        kind = next((k for k in (POINT, DIRECTION, ORIENTATION) if key in k), None)
        side = GROUND_SIDE.get(key)
        if side is not None and getattr(item, side[0], None) == GROUND:
            kind = side[1]
        if key in POINT_SETS and value is not None:
            placed[key] = np.array([frame.point(row) for row in value])
            continue
        placed[key] = value if kind is None or value is None else frame.vector(kind, value)
    return placed


def _initial(frame: Frame, initial):
    """A spherical joint's initial rotation and angular velocity, given in the component's
    axes (its joint frame), in the parent's: R q R^T and R w; other values are relative."""
    if not frame.rotated or not initial:
        return initial
    placed = dict(initial)
    if "orientation" in placed:
        back = np.array([frame.euler_parameters[0], *(-np.asarray(frame.euler_parameters[1:]))])
        placed["orientation"] = quaternion_product(frame.orientation(placed["orientation"]),
                                                   back)
    if "angular_velocity" in placed:
        placed["angular_velocity"] = frame.direction(placed["angular_velocity"])
    return placed


def joint(frame: Frame, names: Names, given: resolved.Joint) -> resolved.Joint:
    point = given.reaction_point
    return replace(given, name=names(given.name), body_i=names(given.body_i),
                   body_j=names(given.body_j), vectors=_vectors(frame, given, given.vectors),
                   reaction_point=None if point is None else frame.point(point),
                   initial=_initial(frame, given.initial),
                   couples=tuple((names(name), use) for name, use in given.couples))


def force(frame: Frame, names: Names, given: resolved.Force) -> resolved.Force:
    value = tuple(map(names.function, given.value)) if given.value else given.value
    if value and given.frame == "global":
        value = rotate_functions(frame, value)
    return replace(given, name=names(given.name), body_i=names(given.body_i),
                   body_j=names(given.body_j), body=names(given.body), joint=names(given.joint),
                   vectors=_vectors(frame, given, given.vectors or {}) or given.vectors,
                   actuator=names.function(given.actuator), value=value)


def place(frame: Frame, prefix: str, model: resolved.ResolvedModel):
    """(bodies, joints, forces) of a resolved component, placed and named."""
    members = {b.name for b in model.bodies} | {j.name for j in model.joints}
    names = Names(prefix, members)
    return (tuple(body(frame, names, b) for b in model.bodies),
            tuple(joint(frame, names, j) for j in model.joints),
            tuple(force(frame, names, f) for f in model.forces))
