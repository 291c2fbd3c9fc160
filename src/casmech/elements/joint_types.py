"""The joint registry: one entry per joint type (`JointType`), read by every stage.

An entry says everything casmech knows about a type: its YAML keys (schema/spec.py builds the
type's pydantic class from them), further checks of its vectors (schema/connections.py), its
constraint rows as primitives and its reaction point (model/lower.py), its free motions,
i.e. the coordinate kinds a driver, motor, rsda, stop, control or force law acts along (each
kind's entry of elements/coordinate_kinds.py, `COORDINATES`, says how), and
its tree motion in the joint formulation (`MOTIONS`; formulations/tree.py, articulated.py).
Adding a joint type is `register(JointType(...))` (docs/architecture.md, "Adding a joint type";
tests/unit/elements/test_joint_registry.py registers one).

Row templates: a primitive kind, for each vector key of that primitive a joint-frame quantity
and the body whose frame it is expressed in, and a label. Joint-frame quantities are GLOBAL at
t = 0 (the file's pose): P (the joint point `at`), Q (`at_j` of revolute_spherical), Pi/Pj
(`at_i`/`at_j`), u, v, w (orthonormal triad, w = axis; the global axes without an axis),
axis_i/axis_j (universal), ex/ey/ez (global unit vectors, used as CD's constant c). `@i` / `@j`
turn a global point or direction into body i's / j's frame; a bare name is used as written (the
basic constraints' body-frame vectors).

Each table was checked against Haug (1989) ch. 9 and the ME751 joint definitions:
spherical = 3 CD; universal = spherical + DP1; revolute = spherical + 2 DP1;
cylindrical = 2 DP1 + 2 DP2; translational = cylindrical + DP1; fixed = spherical + 3 DP1;
plus distance (D), revolute_spherical (D + DP2) and planar (2 DP1 + DP2).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import field
from types import MappingProxyType
from typing import Any

import casadi as ca
import numpy as np

from casmech.core.quaternions import IDENTITY, about, angle_about, from_matrix, product, unit
from casmech.core.records import record
from casmech.core.registry import Registry
from casmech.core.states import JOINT_STATES
from casmech.elements import coordinate_kinds, couplings
from casmech.elements.motions import (
    FREE,
    Motion,
    about_z,
    no_translation,
    slide,
    universal_angles,
    universal_spin,
    universal_turn,
)

Template = tuple[str, dict[str, str], str]  # (kind, {vector key: quantity@body}, label)
Problem = tuple[str, str, str, dict]  # (code, key, message, {got/hint: text}) of a check
ZERO = 1e-12  # a vector shorter than this is zero-length (schema.checker.ZERO)
PERPENDICULAR = 1e-6  # |cos| above which two axes are not perpendicular


# the coordinate kinds (elements/coordinate_kinds.py: a kind's driver row, motor modes, stop,
# state names and measure): what a type's `coordinates` name
COORDINATES = coordinate_kinds.REGISTRY
# YAML vector key -> joint-frame quantity; a new point key may name a new quantity (a point),
# a direction must map to axis_i / axis_j (model/lower.DIRECTIONS)
FRAME = MappingProxyType({"at": "P", "at_i": "Pi", "at_j": "Pj", "axis": "w",
                          "axis_i": "axis_i", "axis_j": "axis_j"})


@record
class Couples:
    """A coupling between joint coordinates (elements/couplings.py): a type whose one row is
    sum_k c_k s_k = 0 over the coordinates s_k of the joints it names, over their bodies."""

    joints: tuple[str, ...]  # YAML keys naming one joint each; (): a `joints:` list of 2 or 3
    uses: tuple[str, ...]  # the coordinate each keyed joint gives (a `joints:` list: any one)
    scalars: tuple[str, ...]  # its scalar keys (a `joints:` list: `coefficients:` beside it)
    coefficients: Callable[[Mapping[str, object]], tuple]  # its scalars -> c_k per coordinate
    output: int  # the coupled joint whose body_j the row's reaction columns are on
    column: str  # the results column `<name>.<column>`: -lambda, the row's generalized force
    # on the output coordinate divided by its coefficient (docs/format.md)
    label: str = ""


@record
class JointType:
    """One joint type (module docstring)."""

    name: str  # YAML `type:`
    # its vector keys, in the order of the YAML class's fields; axis, axis_i, axis_j are unit
    # directions, a_i, a_j, c nonzero ones (schema/connections.py), any other name a point
    vectors: tuple[str, ...]
    rows: tuple[Template, ...]  # its constraint rows
    reaction_point: str | None = "P"  # quantity on body i the reaction torque is taken about
    # (a key of `vectors` for basic constraints; None: body i's origin)
    coordinates: tuple[str, ...] = ()  # coordinate kinds (COORDINATES): what rotates, slides
    limit: str | None = None  # the coordinate a `limit:` stops (None: no `limit:` key)
    motion: Motion | None = None  # tree joint of the joint formulation (None: always cut)
    basic: bool = False  # a basic constraint: `f:` and body-frame vectors, no driver/motor
    options: tuple[str, ...] = ()  # optional scalar keys (distance: `length`)
    frame: Mapping[str, str] = field(default_factory=lambda: FRAME)  # YAML key -> quantity
    arm: tuple[str, str] | None = None  # D rows: |second - first|^2 at t = 0 (or `length`^2)
    check: Callable[[Mapping[str, np.ndarray]], list[Problem]] | None = None
    title: str = ""  # name of the YAML class (default: CamelCase of name)
    # state attributes beyond its coordinates' (casmech.core.states.JOINT_STATES: a universal
    # joint's two angles, a spherical joint's relative rotation and angular velocity)
    states: tuple[str, ...] = ()
    # `initial:` keys beyond its coordinates' values and rates: a universal joint's two
    # angles and rates, a spherical joint's `orientation` and `angular_velocity`
    # (model/initial.py poses the bodies from them)
    initial: tuple[str, ...] = ()
    couples: Couples | None = None  # a coupling of other joints' coordinates (no bodies of its own)
    # joint-frame quantities from its scalar `options` (used as written by its rows: a screw's
    # coefficients from its lead)
    constants: Callable[[Mapping[str, object]], Mapping[str, np.ndarray]] | None = None
    # whether `initial:` may pose it
    posable: bool = True
    # coordinates that follow from another by the type's options: coordinate -> (the one it
    # follows, options -> the ratio). `initial:` gives only the other; posing (model/initial.py)
    # moves the joint's body along both, so the joint is a posing tree's edge
    # (elements/joint_tree.py) though the joint formulation's tree cuts it (a screw's
    # displacement: lead / (2 pi) times its angle)
    follows: Mapping[str, tuple[str, Callable[[Mapping[str, Any]], Any]]] = field(
        default_factory=dict)

    @property
    def class_name(self) -> str:
        return self.title or "".join(part.title() for part in self.name.split("_"))


# a spherical joint's tree velocities: body_j's angular velocity relative to body_i in
# body_j's joint frame (formulations.articulated), which the results columns `wx`, `wy`, `wz`
# give in body_i's
SPHERICAL_VELOCITIES = ("wx_j", "wy_j", "wz_j")


def _cd(axis: str) -> Template:
    return ("cd", {"c": f"e{axis}", "s_i": "P@i", "s_j": "P@j"}, f"joint point, global {axis}")


SPHERICAL = (_cd("x"), _cd("y"), _cd("z"))
PARALLEL = (
    ("dp1", {"a_i": "u@i", "a_j": "w@j"}, "axis_j . u_i = 0"),
    ("dp1", {"a_i": "v@i", "a_j": "w@j"}, "axis_j . v_i = 0"),
)
NO_SPIN = (("dp1", {"a_i": "u@i", "a_j": "v@j"}, "u_i . v_j = 0 (no rotation about the axis)"),)
ON_AXIS = (
    ("dp2", {"a_i": "u@i", "s_i": "P@i", "s_j": "P@j"}, "u_i . d_ij = 0 (point on the axis)"),
    ("dp2", {"a_i": "v@i", "s_i": "P@i", "s_j": "P@j"}, "v_i . d_ij = 0 (point on the axis)"),
)


def check_universal(vectors) -> list[Problem]:
    cosine = abs(vectors["axis_i"] @ vectors["axis_j"])
    if cosine > PERPENDICULAR:
        return [("E405", "axis_j", "axis_i and axis_j must be perpendicular",
                 {"got": f"|cos| = {cosine:.3g}"})]
    return []


def check_revolute_spherical(vectors) -> list[Problem]:
    arm = vectors["at_j"] - vectors["at"]
    length = np.linalg.norm(arm)
    if length < ZERO:
        return [("E404", "at_j", "at_j coincides with at",
                 {"hint": "the arm from `at` to `at_j` must have a positive length"})]
    if abs(arm @ vectors["axis"]) > PERPENDICULAR * length:
        return [("E405", "at_j", "at_j - at must be perpendicular to axis",
                 {"got": f"|cos| = {abs(arm @ vectors['axis']) / length:.3g}"})]
    return []


SCREW = ("angle", "displacement")  # the screw row's coordinates, over the joint's own bodies
SCREW_ROW = (couplings.kind("".join(COORDINATES[c].letter for c in SCREW), (0, 1, 0, 1)),
             {f"{key}{k}": where for k, c in enumerate(SCREW)
              for key, where in COORDINATES[c].vectors.items()} | {"c": "screw"},
             "angle = 2 pi displacement / lead")


def screw_constants(options) -> dict[str, np.ndarray]:
    """The screw row's coefficients: angle - 2 pi displacement / lead = 0."""
    return {"screw": np.array([1.0, -2 * np.pi / options["lead"], 0.0], dtype=object)}


def _coupling(name: str, joints: tuple[str, ...], uses: tuple[str, ...],
              scalars: tuple[str, ...], coefficients, output: int, column: str,
              label: str) -> JointType:
    return JointType(name, (), (), reaction_point=None,
                     couples=Couples(joints, uses, scalars, coefficients, output, column, label))


def _basic(name: str, vectors: tuple[str, ...], label: str, point: str | None) -> JointType:
    return JointType(name, vectors, ((name, {key: key for key in vectors}, label),),
                     reaction_point=point, basic=True, title=name.upper())


BUILT_IN = (
    JointType("revolute", ("at", "axis"), SPHERICAL + PARALLEL, coordinates=("angle",),
              limit="angle",
              motion=Motion(1, 1, lambda th: about(2, th[0]), no_translation,
                            lambda r, d: np.array([angle_about(r, 2)]), drivers={"angle": 0},
                            **about_z(0))),
    JointType("spherical", ("at",), SPHERICAL, states=JOINT_STATES["spherical"],
              initial=("orientation", "angular_velocity"),
              motion=Motion(4, 3, lambda th: unit(th[0:4]), no_translation,
                            lambda r, d: from_matrix(r), quaternions=(0,),
                            names=(JOINT_STATES["spherical"][:4], SPHERICAL_VELOCITIES))),
    JointType("universal", ("at", "axis_i", "axis_j"),
              SPHERICAL + (("dp1", {"a_i": "axis_i@i", "a_j": "axis_j@j"},
                            "axis_i . axis_j = 0 (cross)"),),
              check=check_universal, states=JOINT_STATES["universal"],
              initial=JOINT_STATES["universal"],
              motion=Motion(2, 2, lambda th: product(about(0, th[0]), about(1, th[1])),
                            no_translation, universal_angles, frame="cross",
                            names=(JOINT_STATES["universal"][0::2],
                                   JOINT_STATES["universal"][1::2]),
                            turn=universal_turn, spin=universal_spin)),
    JointType("cylindrical", ("at", "axis"), PARALLEL + ON_AXIS,
              coordinates=("angle", "displacement"), limit="displacement",
              motion=Motion(2, 2, lambda th: about(2, th[0]), slide,
                            lambda r, d: np.array([angle_about(r, 2), d[2]]),
                            drivers={"angle": 0, "displacement": 1},
                            **about_z(0))),
    JointType("translational", ("at", "axis"), PARALLEL + ON_AXIS + NO_SPIN,
              coordinates=("displacement",), limit="displacement",
              motion=Motion(1, 1, lambda th: IDENTITY, slide, lambda r, d: np.array([d[2]]),
                            drivers={"displacement": 0})),
    JointType("screw", ("at", "axis"), PARALLEL + ON_AXIS + (SCREW_ROW,),
              coordinates=("angle", "displacement"), limit="displacement", options=("lead",),
              constants=screw_constants,
              follows={"displacement": ("angle", lambda options: options["lead"] / (2 * np.pi))}),
    JointType("fixed", ("at",), SPHERICAL + PARALLEL + NO_SPIN,
              motion=Motion(0, 0, lambda th: IDENTITY, no_translation,
                            lambda r, d: np.zeros(0))),
    JointType("distance", ("at_i", "at_j"),
              (("d", {"s_i": "Pi@i", "s_j": "Pj@j"}, "|d_ij|^2 = length^2"),),
              reaction_point="Pi", options=("length",), arm=("Pi", "Pj")),
    JointType("revolute_spherical", ("at", "axis", "at_j"),
              (("d", {"s_i": "P@i", "s_j": "Q@j"}, "|d_ij|^2 = length^2"),
               ("dp2", {"a_i": "w@i", "s_i": "P@i", "s_j": "Q@j"}, "axis_i . d_ij = 0")),
              frame=FRAME | {"at_j": "Q"}, arm=("P", "Q"), check=check_revolute_spherical),
    JointType("planar", ("at", "axis"),
              PARALLEL + (("dp2", {"a_i": "w@i", "s_i": "P@i", "s_j": "P@j"},
                           "normal_i . d_ij = 0"),),
              motion=Motion(3, 3, lambda th: about(2, th[2]),
                            lambda th: ca.vertcat(th[0], th[1], 0),
                            lambda r, d: np.array([d[0], d[1], angle_about(r, 2)]),
                            names=(("x", "y", "angle"), ("x_dot", "y_dot", "angle_dot")),
                            **about_z(2))),
    # couplings of joint coordinates (elements/couplings.py)
    _coupling("gear", ("joint_i", "joint_j"), ("angle", "angle"), ("ratio",),
              lambda s: (-s["ratio"], 1.0), 1, "torque", "angle_j = ratio angle_i"),
    _coupling("rack_pinion", ("joint_i", "joint_j"), ("angle", "displacement"), ("radius",),
              lambda s: (-s["radius"], 1.0), 1, "force", "displacement_j = radius angle_i"),
    _coupling("coupler", (), (), (), lambda s: tuple(s["coefficients"]), 0, "force",
              "sum of coefficients times coordinates = offset"),
    # basic constraints: the file's vectors are used as written (body frames; c global)
    _basic("dp1", ("a_i", "a_j"), "a_i . a_j = f(t)", None),
    _basic("dp2", ("a_i", "s_i", "s_j"), "a_i . d_ij = f(t)", "s_i"),
    _basic("d", ("s_i", "s_j"), "d_ij . d_ij = f(t)", "s_i"),
    _basic("cd", ("c", "s_i", "s_j"), "c . d_ij = f(t)", "s_i"),
)

REGISTRY: Registry = Registry(BUILT_IN)  # name -> JointType
# register(entry) adds or replaces a type, unregister(name) removes it, on_change(listener)
# follows both (casmech.core.registry)
register, unregister, on_change = REGISTRY.register, REGISTRY.unregister, REGISTRY.on_change


def having(coordinate: str) -> tuple[str, ...]:
    """The joint types with this free coordinate ("angle": they rotate about their axis,
    "displacement": they slide along it): those with no other first, else in registry order."""
    found = [entry for entry in REGISTRY.values() if coordinate in entry.coordinates]
    return tuple(entry.name for entry in sorted(found, key=lambda e: len(e.coordinates)))


def attributes(joint_type: str) -> list[str]:
    """The state attributes a joint of this type has (`angle`, `angle_dot`, ..., then its
    entry's `states`; casmech.core.states)."""
    entry = REGISTRY.get(joint_type)
    if entry is None:
        return []
    return list(_coordinate_attributes(entry, ())) + list(entry.states)


def state_names(joint_type: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(names of the coordinates theta, of the velocities u) of a tree joint of this type
    ("free": a floating body's) in the joint formulation: its Motion's `names`, else each
    coordinate kind's value and rate at the index its `drivers` give (`q<k>`, `u<k>` where
    neither names one). Where a name is one of the joint's state attributes, the entry is
    that results column's value (tests/unit/formulations/test_state_names.py)."""
    motion = MOTIONS[joint_type]
    if motion.names is not None:
        return motion.names
    q_names = [f"q{k}" for k in range(motion.n_q)]
    v_names = [f"u{k}" for k in range(motion.n_v)]
    for kind, index in motion.drivers.items():
        q_names[index], v_names[index] = COORDINATES[kind].attributes
    return tuple(q_names), tuple(v_names)


def initial_keys(joint_type: str) -> tuple[str, ...]:
    """The keys of a joint type's `initial:` (its coordinates' values and rates, then its
    entry's `initial`); none for a type that cannot be posed by its joint values."""
    entry = REGISTRY.get(joint_type)
    if entry is None or entry.basic or not entry.posable:
        return ()
    return _coordinate_attributes(entry, entry.follows) + entry.initial


def _coordinate_attributes(entry: JointType, leaving=()) -> tuple[str, ...]:
    """The values and rates of an entry's coordinates but those in `leaving`, in the kinds'
    registry order (`initial:` leaves a coordinate that follows another: a screw's slide)."""
    return tuple(attribute for name, kind in COORDINATES.items()
                 if name in entry.coordinates and name not in leaving
                 for attribute in kind.attributes)


def coordinate_types() -> tuple[str, ...]:
    """The joint types with any free coordinate, in registry order."""
    return tuple(name for name, entry in REGISTRY.items() if entry.coordinates)


def listed(names, last: str = "and") -> str:
    """'revolute, cylindrical and translational'."""
    names = list(names)
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} {last} {names[-1]}"


class _Motions(Mapping):
    """joint type -> its tree Motion (types without one are always cut), and "free"."""

    def __getitem__(self, kind: str) -> Motion:
        if kind == "free":
            return FREE
        motion = REGISTRY[kind].motion
        if motion is None:
            raise KeyError(kind)
        return motion

    def __iter__(self) -> Iterator[str]:
        yield from (name for name, entry in REGISTRY.items() if entry.motion is not None)
        yield "free"

    def __len__(self) -> int:
        return sum(1 for _ in self)


MOTIONS: Mapping[str, Motion] = _Motions()
