"""The coordinate kinds: a joint's free motions (its coordinates, 0 at the file's pose) and
everything casmech knows about each, declared once in a `CoordinateKind` entry.

A joint type lists the kinds it has (`JointType.coordinates`, elements/joint_types.py); every
stage reads the kind's entry:

- its name is the joint's state attribute `<joint>.<name>` with its rate `<name>_dot`
  (force laws, events, results columns: casmech.core.states and core.columns are filled from
  here), the `driver:` key and the `initial:` keys;
- `measure` is the one formula of its value over the joint's two body frames and the vectors
  `vectors` names (the joint frame's quantities carried by body i or j); its rate is its time
  derivative by AD (equations/coordinates.py), and an effort motor, a stop, joint friction,
  a control input and a coupling row all act along it (virtual work: s_q^T f);
- `driver` is the row `driver: {<name>: f(t)}` adds (a primitive of elements/primitives.py);
- `motor` its motor modes (position, speed, effort: schema/motors.py); the effort mode names
  the effort motor's ForceIR type `motor_<effort>`, the stop's results column
  `limit_<effort>`; the stop's ForceIR type is `limit_<name>`, the friction's
  `friction_<name>`;
- `quantity` what it measures (an angle or a length): the dimensions and SI units of its
  value, rate, effort, stop stiffness and damping (units in expressions, results columns);
- `pose` moves body j relative to body i by a value, about the joint point: how `initial:`
  poses the bodies (model/initial.py);
- `letter` names it in a coupling row's kind (elements/couplings.py); `cos_sin`, for a kind
  that comes back to itself after a turn, gives (cos, sin) of its value for the couplings'
  turn-continuous rows.

Adding a kind is `register(CoordinateKind(...))` (docs/architecture.md, "Adding a coordinate
kind"; tests/unit/elements/test_coordinate_kinds.py registers one).

The built-in kinds: angle, the rotation of body j about the joint axis, atan2(v_i . u_j,
u_i . u_j) (u_i, v_i on body i, u_j on body j: the joint frame's u, v at the file's pose), in
(-pi, pi]; displacement, the slide of body j's joint point along the axis carried by body i,
w_i . (P_j - P_i).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping

import casadi as ca

from casmech.core import columns, states
from casmech.core.records import record
from casmech.core.registry import Registry
from casmech.core.units import (
    DAMPING,
    FORCE,
    LENGTH,
    NUMBER,
    RATE,
    ROTATIONAL_DAMPING,
    STIFFNESS,
    TORQUE,
    VELOCITY,
    Dimension,
)
from casmech.elements.forces.terms import relative_angle

ROLES = ("effort", "limit", "friction")  # the ForceIR types a kind names (CoordinateKind.types)
# the roles whose law reads t and its joint's coordinate and rate only, the relative motion of
# the joint's two bodies (a friction's also reads the runtime's mode and the joint's load)
RELATIVE_ROLES = ("effort", "limit")


@record
class Quantity:
    """What a coordinate measures: the dimensions and SI units of its value and what acts
    along it."""

    name: str  # "angle" | "length" (schema/check_only.py bounds a driver by it)
    value: Dimension
    rate: Dimension
    effort: Dimension  # what acts along it: an effort motor's law, a stop's or friction's force
    stiffness: Dimension  # a stop's stiffness
    damping: Dimension  # a stop's damping
    units: tuple[str, str, str]  # SI units of the value, rate and acceleration
    effort_unit: str  # SI unit of the effort (a stop's or a friction's column)


ANGLE = Quantity("angle", NUMBER, RATE, TORQUE, TORQUE, ROTATIONAL_DAMPING,
                 ("rad", "rad/s", "rad/s^2"), "N m")
DISTANCE = Quantity("length", LENGTH, VELOCITY, FORCE, STIFFNESS, DAMPING,
                    ("m", "m/s", "m/s^2"), "N")


@record
class CoordinateKind:
    """One coordinate kind (module docstring)."""

    name: str
    measure: Callable  # (frame_i, frame_j, *vectors in `vectors` order) -> value
    vectors: Mapping[str, str]  # measure's vector key -> joint-frame quantity@body (P: point)
    driver: tuple  # (primitive kind, {vector key: quantity@body}, label) of its driver row
    motor: tuple[str, str, str]  # motor modes: position, speed, effort
    quantity: Quantity
    letter: str  # one letter naming it in a coupling row's kind
    # results column (quantity, title) of its value and of its rate
    columns: tuple[tuple[str, str], tuple[str, str]]
    # (quantity -> the joint frame's global quantity at t = 0, value) -> (Euler parameters or
    # None, translation or None): the rigid motion of body j relative to body i by the value,
    # about the joint point, that poses `initial:` (model/initial.py)
    pose: Callable
    cos_sin: Callable | None = None  # (frame_i, frame_j, *vectors) -> (cos, sin) of the value

    @property
    def rate(self) -> str:
        return f"{self.name}_dot"

    @property
    def attributes(self) -> tuple[str, str]:
        """Its state attributes: the value and its rate."""
        return self.name, self.rate

    @property
    def effort(self) -> str:
        return f"motor_{self.motor[2]}"

    @property
    def limit(self) -> str:
        return f"limit_{self.name}"

    @property
    def friction(self) -> str:
        return f"friction_{self.name}"

    @property
    def column(self) -> str:
        """Results column of its stop's force or torque."""
        return f"limit_{self.motor[2]}"

    @property
    def types(self) -> dict[str, str]:
        """role (ROLES) -> ForceIR type."""
        return {"effort": self.effort, "limit": self.limit, "friction": self.friction}

    def points(self) -> tuple[str, ...]:
        return tuple(key for key, where in self.vectors.items() if where.startswith("P@"))

    def value(self, frame_i, frame_j, geometry: Mapping):
        """The measure over two frames and a geometry holding its vectors by key."""
        return self.measure(frame_i, frame_j, *(geometry[key] for key in self.vectors))


def angle_value(fi, fj, u_i, v_i, u_j):
    """The angle of a joint over its bodies' frames (module docstring)."""
    return relative_angle(fi.A, fj.A, u_i, v_i, u_j)


def angle_cos_sin(fi, fj, u_i, v_i, u_j):
    """(cos, sin) of a joint's angle, without atan2."""
    u_j = fj.A @ u_j
    return (fi.A @ u_i).T @ u_j, (fi.A @ v_i).T @ u_j


def slide_value(fi, fj, w, s_i, s_j):
    """The slide of body j's point s_j along the direction w carried by body i, from body i's
    point s_i: w_i . (P_j - P_i)."""
    gap = fj.r + fj.A @ s_j - fi.r - fi.A @ s_i
    return (fi.A @ w).T @ gap


def turn(frame, angle):
    """A rotation by the angle about the joint axis w."""
    return ca.vertcat(ca.cos(angle / 2), ca.sin(angle / 2) * frame("w")), None


def shift(frame, slide):
    """A translation by the slide along the joint axis w."""
    return None, slide * frame("w")


BUILT_IN = (
    CoordinateKind("angle", angle_value, {"u_i": "u@i", "v_i": "v@i", "u_j": "u@j"},
                   ("angle", {"u_i": "u@i", "v_i": "v@i", "u_j": "u@j"},
                    "rotation angle = f(t)"),
                   ("angle", "speed", "torque"), ANGLE, "a",
                   (("joint angle", "joint angles (0 at the file's pose)"),
                    ("joint angular rate", "joint angular rates")),
                   turn, cos_sin=angle_cos_sin),
    CoordinateKind("displacement", slide_value, {"w_i": "w@i", "s_i": "P@i", "s_j": "P@j"},
                   ("dp2", {"a_i": "w@i", "s_i": "P@i", "s_j": "P@j"}, "slide = f(t)"),
                   ("displacement", "velocity", "force"), DISTANCE, "d",
                   (("joint displacement", "joint displacements (0 at the file's pose)"),
                    ("joint velocity", "joint sliding velocities")), shift),
)

REGISTRY: Registry = Registry(BUILT_IN)  # name -> CoordinateKind
register, unregister, on_change = REGISTRY.register, REGISTRY.unregister, REGISTRY.on_change


class View(Mapping):
    """A table derived from the registry, rebuilt after every change of it."""

    def __init__(self, build: Callable[[], Mapping]):
        self.build, self.table = build, None
        on_change(self.reset)

    def reset(self) -> None:
        self.table = None

    def now(self) -> Mapping:
        if self.table is None:
            self.table = dict(self.build())
        return self.table

    def __getitem__(self, key):
        return self.now()[key]

    def __iter__(self) -> Iterator:
        return iter(self.now())

    def __len__(self) -> int:
        return len(self.now())


# ForceIR type (an effort motor, a stop, a joint friction) -> (its kind, its role in ROLES)
BY_TYPE: Mapping[str, tuple[CoordinateKind, str]] = View(
    lambda: {kind_type: (kind, role) for kind in REGISTRY.values()
             for role, kind_type in kind.types.items()})
# motor mode -> (the kind it acts along, its index: 0 position, 1 speed, 2 effort)
BY_MODE: Mapping[str, tuple[CoordinateKind, int]] = View(
    lambda: {mode: (kind, k) for kind in REGISTRY.values() for k, mode in enumerate(kind.motor)})
BY_LETTER: Mapping[str, CoordinateKind] = View(
    lambda: {kind.letter: kind for kind in REGISTRY.values()})


def of_type(role: str) -> Mapping[str, str]:
    """ForceIR type of this role -> the name of the kind it acts along (a view)."""
    return View(lambda: {kind.types[role]: kind.name for kind in REGISTRY.values()})


# ------------------------------------------------------------------- the tables of core
WRITTEN: list[tuple[dict, str]] = []  # (table of casmech.core, key) written by _declare


def _write(table: dict, key: str, value) -> None:
    if key not in table:
        table[key] = value
        WRITTEN.append((table, key))


def _declare() -> None:
    """Write the registered kinds' state names and results columns into casmech.core's tables
    (core imports nothing of elements; it holds what is registered here)."""
    for table, key in WRITTEN:
        table.pop(key, None)
    WRITTEN.clear()
    for kind in REGISTRY.values():
        for attribute, (quantity, title), unit in zip(kind.attributes, kind.columns,
                                                      kind.quantity.units, strict=False):
            _write(states.JOINT_COORDINATES, attribute, kind.name)
            _write(states.JOINT_QUANTITIES, attribute, attribute)
            _write(columns.QUANTITIES, attribute, (quantity, unit, title))
        effort = kind.motor[2]
        _write(columns.QUANTITIES, kind.column, (f"stop {effort}", kind.quantity.effort_unit,
                                                 f"joint stop {effort} along the joint axis"))


_declare()
on_change(_declare)
