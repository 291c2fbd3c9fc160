"""Adams units and frames: UNITS -> SI factors, PART/MARKER placements -> global frames.

- REULER = a, b, c: body-fixed 3-1-3 Euler angles (about z, the new x, the new z); radians
  unless a value carries a D suffix (degrees) — Adams/Solver's rule. A bare non-zero angle is
  therefore radians, which is worth a warning since decks mostly write degrees.
- ZP/XP (markers) and ZG/XG (parts): a point on the +z axis and one in the +x/z half-plane.
- A marker's QP/REULER are in its part's frame; a part's QG/REULER are global.
"""

from __future__ import annotations

import numpy as np

from casmech.core.records import record

# SI value of one unit (Adams UNITS keywords)
LENGTH = {"METER": 1.0, "MILLIMETER": 1e-3, "CENTIMETER": 1e-2, "KILOMETER": 1e3,
          "INCH": 0.0254, "FOOT": 0.3048, "MILE": 1609.344}
MASS = {"KILOGRAM": 1.0, "GRAM": 1e-3, "MEGAGRAM": 1e3, "POUND_MASS": 0.45359237,
        "KPOUND_MASS": 453.59237, "SLUG": 14.593902937, "OUNCE_MASS": 0.028349523125}
FORCE = {"NEWTON": 1.0, "KILONEWTON": 1e3, "MILLINEWTON": 1e-3, "DYNE": 1e-5,
         "POUND_FORCE": 4.4482216152605, "KPOUND_FORCE": 4448.2216152605,
         "OUNCE_FORCE": 0.27801385095378, "KILOGRAM_FORCE": 9.80665}
TIME = {"SECOND": 1.0, "MILLISECOND": 1e-3, "MINUTE": 60.0, "HOUR": 3600.0}
# UNITS/SYSTEM = ... : (force, mass, length, time)
SYSTEMS = {"MKS": ("NEWTON", "KILOGRAM", "METER", "SECOND"),
           "MMKS": ("NEWTON", "KILOGRAM", "MILLIMETER", "SECOND"),
           "CGS": ("DYNE", "GRAM", "CENTIMETER", "SECOND"),
           "IPS": ("POUND_FORCE", "POUND_MASS", "INCH", "SECOND"),
           "FPS": ("POUND_FORCE", "POUND_MASS", "FOOT", "SECOND")}
TABLES = {"FORCE": FORCE, "MASS": MASS, "LENGTH": LENGTH, "TIME": TIME}


@record
class Units:
    """SI factors of the deck's base units."""

    force: float = 1.0
    mass: float = 1.0
    length: float = 1.0
    time: float = 1.0

    @property
    def inertia(self) -> float:
        return self.mass * self.length**2

    @property
    def velocity(self) -> float:
        return self.length / self.time

    @property
    def acceleration(self) -> float:
        return self.length / self.time**2

    @property
    def stiffness(self) -> float:  # force / length
        return self.force / self.length

    @property
    def damping(self) -> float:  # force time / length
        return self.force * self.time / self.length

    @property
    def torque(self) -> float:  # force length (per radian)
        return self.force * self.length


def euler_313(a: float, b: float, c: float) -> np.ndarray:
    """Rotation matrix (columns = rotated axes in the parent frame) of body-fixed 3-1-3 angles."""
    def rz(x):
        return np.array([[np.cos(x), -np.sin(x), 0], [np.sin(x), np.cos(x), 0], [0, 0, 1]])

    def rx(x):
        return np.array([[1, 0, 0], [0, np.cos(x), -np.sin(x)], [0, np.sin(x), np.cos(x)]])

    return rz(a) @ rx(b) @ rz(c)


def from_points(origin, z_point, x_point) -> np.ndarray | None:
    """Frame from a point on +z and (optionally) one in the +x/z half-plane; None if degenerate."""
    z = np.asarray(z_point, float) - origin
    if np.linalg.norm(z) == 0:
        return None
    z = z / np.linalg.norm(z)
    if x_point is None:  # Adams: x in the plane of z and the parent x axis (or y if parallel)
        helper = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    else:
        helper = np.asarray(x_point, float) - origin
    x = helper - (helper @ z) * z
    if np.linalg.norm(x) == 0:
        return None
    x = x / np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


@record
class Frame:
    """A placement in the global frame: origin and rotation (columns = axes)."""

    origin: np.ndarray
    rotation: np.ndarray

    def point(self, local) -> np.ndarray:
        return self.origin + self.rotation @ np.asarray(local, float)

    def compose(self, local: Frame) -> Frame:
        return Frame(self.point(local.origin), self.rotation @ local.rotation)

    def axis(self, k: int) -> np.ndarray:
        return self.rotation[:, k]

    def to_local_point(self, point) -> np.ndarray:
        return self.rotation.T @ (np.asarray(point, float) - self.origin)

    def to_local_vector(self, vector) -> np.ndarray:
        return self.rotation.T @ np.asarray(vector, float)


IDENTITY = Frame(np.zeros(3), np.eye(3))


def tidy(values, scale: float = 1.0) -> list[float]:
    """Plain floats, with roundoff below 1e-14 * scale written as exact zeros and +-1."""
    out = []
    for v in np.asarray(values, float).ravel():
        v = float(v)
        if abs(v) < 1e-14 * scale:
            v = 0.0
        elif abs(abs(v) - 1) < 1e-15:
            v = float(np.sign(v))
        out.append(v)
    return out
