"""ModelIR: the mechanism with names turned into indices and joints expanded into primitives.

Body index -1 is ground. Every vector here is in the frame the primitive expects (body-frame
`_bar` vectors, global `c`); every constraint row carries its provenance (joint, YAML source).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import field
from typing import Any

import numpy as np

from casmech.core.records import record
from casmech.errors import Source
from casmech.schema.resolved import Analysis, Output, ScalarFunction

GROUND_INDEX = -1


@record
class RowInfo:
    """Provenance of one constraint row."""

    joint: str  # joint name, or the body name for a normalization row
    kind: str  # dp1 | dp2 | d | cd | angle | normalization
    label: str  # human description, e.g. "revolute 'pivot': axis_j . u_i = 0"
    source: Source | None = None


@record
class PrimitiveIR:
    """One basic constraint row of a kind of elements.primitives: its bodies (indices),
    vectors, driving function and offset."""

    kind: str
    body_i: int
    body_j: int
    vectors: Mapping[str, np.ndarray]
    f: ScalarFunction | None  # None means f = 0
    offset: float = 0.0  # constant added to f (e.g. a distance's length squared)
    is_driver: bool = False  # a composite joint's driver: scaled by assembly's continuation
    row: RowInfo = field(default_factory=lambda: RowInfo("", ""))
    others: tuple[int, ...] = ()  # bodies the row reads after body_i and body_j (a coupler)

    @property
    def bodies(self) -> tuple[int, ...]:
        """Every body the row reads, in the order its primitive takes their frames."""
        return (self.body_i, self.body_j, *self.others)


@record
class BodyIR:
    """A lowered body: mass, inertia about its CM in its frame, initial pose and velocities."""

    name: str
    mass: float
    inertia: np.ndarray  # (3, 3) body frame, about the CM
    r0: np.ndarray
    p0: np.ndarray
    r_dot0: np.ndarray
    omega0: np.ndarray  # global
    source: Source | None = None


@record
class JointIR:
    """A joint of the file and the rows of phi it owns."""

    name: str
    type: str
    body_i: int
    body_j: int
    rows: range
    point_i: np.ndarray  # the joint point on body_i, body frame (global for ground)
    source: Source | None = None
    # joint-frame quantities (lower.joint_frame: P, u, v, w, axis_i, axis_j) in each body's
    # frame, keyed "<name>@i" / "<name>@j" (ground: global): the joint formulation's frames
    geometry: Mapping[str, np.ndarray] = field(default_factory=dict)
    drivers: Mapping[str, ScalarFunction] = field(default_factory=dict)  # angle, displacement
    cut: bool = False  # `cut: true`: never a tree joint of the joint formulation
    reaction_frame: str = "global"  # the frame of its reaction columns (runtime.reaction_frames)
    reaction_point: np.ndarray | None = None  # the torque's point instead of point_i, body_i frame
    # `initial:` (schema/initial.py; runtime/initial_holds.py holds them while loops close):
    # key -> value, and where each key was written
    initial: Mapping[str, Any] = field(default_factory=dict)
    initial_sources: Mapping[str, Source] = field(default_factory=dict)
    # a coupling (joint_types.Couples): (joint, coordinate) of each coupled coordinate and
    # its coefficient; body_i, body_j, point_i and geometry are then the output joint's
    couples: tuple[tuple[str, str], ...] = ()
    coefficients: tuple[Any, ...] = ()


@record
class ForceIR:
    """A lowered force element: type, bodies (indices), body-frame points, parameters and
    actuator."""

    name: str
    type: str
    body_i: int
    body_j: int
    points: Mapping[str, np.ndarray]  # body-frame points s_i, s_j (tsda), s (force)
    params: Mapping[str, float]
    actuator: ScalarFunction | None = None
    value: tuple[ScalarFunction, ...] | None = None
    frame: str = "global"
    axes: Mapping[str, np.ndarray] = field(default_factory=dict)  # rsda: u_i, v_i, w_i, u_j
    source: Source | None = None


@record
class ModelIR:
    """The lowered model: bodies, constraint rows (primitives), joints and forces by index,
    with the model's settings."""

    name: str
    file: str
    text: str
    bodies: tuple[BodyIR, ...]
    primitives: tuple[PrimitiveIR, ...]
    joints: tuple[JointIR, ...]
    forces: tuple[ForceIR, ...]
    gravity: np.ndarray
    analysis: Analysis
    parameters: Mapping[str, float] = field(default_factory=dict)
    motors: tuple[ForceIR, ...] = ()  # effort motors of joints (equations/motors.py), by joint name
    limits: tuple[ForceIR, ...] = ()  # joint stops (equations/limits.py), by joint name
    outputs: tuple[Output, ...] = ()  # the model's `outputs:` (equations/readings.py)
    # the file's pose q (r then p of every body) when the joints' `initial:` values moved the
    # bodies away from it (model/initial.py; assembly's continuation starts there), else None
    reference_pose: np.ndarray | None = None

    @property
    def n_bodies(self) -> int:
        return len(self.bodies)

    @property
    def n_coordinates(self) -> int:
        return 7 * len(self.bodies)

    def row_info(self) -> list[RowInfo]:
        """Provenance of every row of phi: joint rows, then one normalization row per body."""
        rows = [p.row for p in self.primitives]
        rows += [RowInfo(b.name, "normalization", f"p^T p - 1 of '{b.name}'", b.source)
                 for b in self.bodies]
        return rows
