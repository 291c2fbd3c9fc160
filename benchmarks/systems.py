"""The benchmark systems, defined once; the casmech, Exudyn and MuJoCo models are generated from
these descriptions (casmech_model.py, exudyn_model.py, mujoco_model.py).

Every body is a uniform bar lying in the global x-y plane at t = 0. Its body frame has its origin
at the CM and its x axis along the bar (from the proximal to the distal end), rotated by `angle`
about global z. Principal moments about the CM in that frame: [I_AXIAL, m L^2/12, m L^2/12].
I_AXIAL = 1e-4 kg m^2 is the same in all three tools: a slender bar has an axial moment close to
zero, but casmech's mass matrix must be positive definite. No body starts moving (every system
is released from rest).

Accuracy is measured on the CM and the distal end ("tip") of every bar: `points()`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

G = 9.81
I_AXIAL = 1.0e-4  # kg m^2, axial moment of every bar
T_END = 10.0  # s, simulated time of every run
T_CHECK = 1.0  # s, time at which the error is measured
OUTPUT_STEP = 0.01  # s, every tool records the trajectory at this period


@dataclass(frozen=True)
class Bar:
    name: str
    length: float
    mass: float
    start: tuple[float, float, float]  # proximal end, global, t = 0
    angle: float  # rotation about global z from +x to the bar's axis, t = 0

    @property
    def axis(self) -> np.ndarray:
        return np.array([math.cos(self.angle), math.sin(self.angle), 0.0])

    @property
    def cm(self) -> np.ndarray:
        return np.array(self.start) + 0.5 * self.length * self.axis

    @property
    def tip(self) -> np.ndarray:
        return np.array(self.start) + self.length * self.axis

    @property
    def inertia(self) -> tuple[float, float, float]:
        transverse = self.mass * self.length**2 / 12.0
        return (I_AXIAL, transverse, transverse)


@dataclass(frozen=True)
class Joint:
    """A joint between `parent` (a bar name or "ground") and `child`, at a global point at
    t = 0. kind: "spherical" | "revolute" (axis: global, t = 0) | "pin_xy" (the joint point
    of the two bodies coincides in global x and y only: the loop-closing joint of a planar
    mechanism without redundant constraints)."""

    name: str
    kind: str
    parent: str
    child: str
    at: tuple[float, float, float]
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)


@dataclass(frozen=True)
class System:
    name: str
    description: str
    bars: list[Bar]
    tree_joints: list[Joint]  # a spanning tree: each bar is the child of exactly one of these
    loop_joints: list[Joint] = field(default_factory=list)  # closing the loops
    gravity: tuple[float, float, float] = (0.0, 0.0, -G)
    # The plane of the motion (by symmetry it stays planar): global directions of the planar
    # axes e1, e2; bar angles in that plane are measured from e1 towards e2 (reference.py).
    plane: tuple[tuple[float, ...], tuple[float, ...]] = ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0))

    def bar(self, name: str) -> Bar:
        return next(b for b in self.bars if b.name == name)

    @property
    def joints(self) -> list[Joint]:
        return self.tree_joints + self.loop_joints


def chain(n: int) -> System:
    """N-link spherical chain: N bars (1 m, 1 kg) along +x from the origin, at rest at t = 0,
    gravity 9.81 in -z; bar1 on ground by a spherical joint at the origin, bar k+1 on the tip
    of bar k by a spherical joint. (By symmetry the motion stays in the x-z plane.)"""
    bars = [Bar(f"bar{k}", 1.0, 1.0, (k - 1.0, 0.0, 0.0), 0.0) for k in range(1, n + 1)]
    joints = [Joint(f"j{k}", "spherical", "ground" if k == 1 else f"bar{k - 1}", f"bar{k}",
                    (k - 1.0, 0.0, 0.0)) for k in range(1, n + 1)]
    return System(f"chain{n}", f"{n}-link spherical chain (1 m, 1 kg bars), released "
                  "horizontally from rest, gravity -z", bars, joints)


# Four-bar: ground pivots O2 = (0, 0, 0) and O4 = (FB_D, 0, 0); crank FB_A (O2-B), coupler FB_B
# (B-C), rocker FB_C (O4-C); Grashof crank-rocker (1 + 2.5 <= 2 + 2). Bars of 1 kg per metre.
# Released from rest with the crank at 45 degrees, open (upper) assembly; gravity 9.81 in -y; all
# revolute axes along z. With the crank and the rocker on ground revolutes and a revolute between
# crank and coupler, the loop is closed at C by the two in-plane components of a pin (pin_xy):
# 3 x 5 + 2 = 17 equations on 3 x 6 coordinates, 1 DOF, no redundant constraint.
FB_A, FB_B, FB_C, FB_D = 1.0, 2.0, 2.0, 2.5
FB_DENSITY = 1.0  # kg/m
FB_CRANK_ANGLE = math.pi / 4


def four_bar_points() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """O4, B and C at t = 0 (open assembly: C above the line B-O4)."""
    o4 = np.array([FB_D, 0.0, 0.0])
    b = FB_A * np.array([math.cos(FB_CRANK_ANGLE), math.sin(FB_CRANK_ANGLE), 0.0])
    # C on the circles |C - B| = FB_B and |C - O4| = FB_C
    d = np.linalg.norm(o4 - b)
    along = (FB_B**2 - FB_C**2 + d**2) / (2.0 * d)
    across = math.sqrt(FB_B**2 - along**2)
    u = (o4 - b) / d
    normal = np.array([-u[1], u[0], 0.0])
    c = b + along * u + across * normal
    if c[1] < 0:
        c = b + along * u - across * normal
    return o4, b, c


def four_bar() -> System:
    o4, b, c = four_bar_points()

    def bar(name, start, end):
        length = float(np.linalg.norm(end - start))
        angle = math.atan2(end[1] - start[1], end[0] - start[0])
        return Bar(name, length, FB_DENSITY * length, tuple(float(x) for x in start), angle)

    origin = np.zeros(3)
    bars = [bar("crank", origin, b), bar("coupler", b, c), bar("rocker", o4, c)]
    as_tuple = lambda p: tuple(float(x) for x in p)  # noqa: E731
    tree = [Joint("crank_pivot", "revolute", "ground", "crank", (0.0, 0.0, 0.0)),
            Joint("coupler_pin", "revolute", "crank", "coupler", as_tuple(b)),
            Joint("rocker_pivot", "revolute", "ground", "rocker", as_tuple(o4))]
    loop = [Joint("loop_pin", "pin_xy", "coupler", "rocker", as_tuple(c))]
    return System("four_bar", "planar four-bar (crank 1, coupler 2, rocker 2, ground 2.5 m; "
                  "1 kg/m), released from rest at crank angle 45 deg, gravity -y",
                  bars, tree, loop, gravity=(0.0, -G, 0.0),
                  plane=((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)))


def make(name: str) -> System:
    """`chain<N>` or `four_bar`."""
    if name == "four_bar":
        return four_bar()
    if name.startswith("chain") and name[5:].isdigit():
        return chain(int(name[5:]))
    raise ValueError(f"unknown system {name!r} (chain<N> or four_bar)")


def rotation_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def points(system: System, cms: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """The measured points, shape (2 * n_bars, 3): the CM then the tip of every bar, from the
    CM positions (n, 3) and the body rotation matrices (n, 3, 3) (columns: body axes)."""
    out = []
    for bar, cm, rot in zip(system.bars, cms, rotations, strict=True):
        out += [cm, cm + rot @ np.array([0.5 * bar.length, 0.0, 0.0])]
    return np.array(out)


def initial_points(system: System) -> np.ndarray:
    return np.array([p for bar in system.bars for p in (bar.cm, bar.tip)])


def error(points_a: np.ndarray, points_b: np.ndarray) -> float:
    """Max Euclidean distance between corresponding points."""
    return float(np.max(np.linalg.norm(np.asarray(points_a) - np.asarray(points_b), axis=1)))
