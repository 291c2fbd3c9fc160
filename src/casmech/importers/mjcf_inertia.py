"""Mass properties of MJCF bodies: `<inertial>` or the geoms (`compiler inertiafromgeom`).

`inertiafromgeom="auto"` (MuJoCo's default) takes a body's mass properties from its
`<inertial>` when it has one, else from its geoms; `"true"` always from the geoms, `"false"`
never. A geom's mass is its `mass`, else `density` (default 1000 kg/m^3) times its volume; its
inertia is that of the solid shape (MuJoCo's formulas: a capsule is a cylinder and two
hemispheres). Geoms outside `compiler inertiagrouprange` (default 0 5) do not count, nor
planes. A mesh geom's mass would need the mesh's volume, which casmech does not compute: such a
geom is left out with a warning.
"""

from __future__ import annotations

import numpy as np

from casmech.core.records import record
from casmech.importers.mjcf_read import Element, Reader
from casmech.importers.urdf_tree import Frame


@record(frozen=False)
class Mass:
    mass: float
    centre: np.ndarray  # in the body frame
    tensor: np.ndarray  # about the centre, in the body frame's axes

    @staticmethod
    def zero() -> Mass:
        return Mass(0.0, np.zeros(3), np.zeros((3, 3)))

    def placed(self, at: Frame) -> Mass:
        """The same mass described in the frame in which `at` is given."""
        return Mass(self.mass, at.point(self.centre), at.rotation @ self.tensor @ at.rotation.T)


def combine(parts: list[Mass]) -> Mass:
    parts = [p for p in parts if p.mass > 0]
    mass = sum(p.mass for p in parts)
    if mass <= 0:
        return Mass.zero()
    centre = sum(p.mass * p.centre for p in parts) / mass
    tensor = np.zeros((3, 3))
    for p in parts:
        d = p.centre - centre
        tensor += p.tensor + p.mass * (d @ d * np.eye(3) - np.outer(d, d))
    return Mass(mass, centre, tensor)


def inertial(reader: Reader, element: Element, frame: Frame, path: str) -> Mass:
    """An `<inertial>` (its frame already read) in the body frame."""
    attrib = element.attrib
    mass = reader.number(element, attrib, "mass", path)
    if mass is None:
        raise reader.error(element, path, "<inertial> has no 'mass'", 'mass="..."',
                           code="E100")
    if mass < 0:
        raise reader.error(element, f"{path}.mass", "the mass is negative", "a mass >= 0 [kg]",
                           code="E400", got=str(mass))
    diagonal = reader.numbers(element, attrib, "diaginertia", path, (3,))
    full = reader.numbers(element, attrib, "fullinertia", path, (6,))
    if (diagonal is None) == (full is None):
        raise reader.error(element, path, "<inertial> needs one of diaginertia and "
                           "fullinertia", 'diaginertia="Ixx Iyy Izz"', code="E100")
    if full is not None:
        xx, yy, zz, xy, xz, yz = full
        tensor = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    else:
        tensor = np.diag(diagonal)
    return Mass(mass, np.zeros(3), tensor).placed(frame)


def _solid(kind: str, size: np.ndarray) -> tuple[float, np.ndarray] | None:
    """Volume and inertia per unit mass (principal, in the geom frame) of a primitive shape."""
    if kind == "sphere":
        r = size[0]
        return 4 / 3 * np.pi * r ** 3, np.full(3, 0.4 * r * r)
    if kind == "capsule":
        r, height = size[0], 2 * size[1]
        volume = np.pi * r * r * height + 4 / 3 * np.pi * r ** 3
        sphere = 4 * r / (4 * r + 3 * height)  # the hemispheres' share of the mass
        cylinder = 1 - sphere
        side = cylinder * (3 * r * r + height * height) / 12 + 0.4 * sphere * r * r \
            + sphere * height * (3 * r + 2 * height) / 8
        return volume, np.array([side, side, cylinder * r * r / 2 + 0.4 * sphere * r * r])
    if kind == "cylinder":
        r, height = size[0], 2 * size[1]
        side = (3 * r * r + height * height) / 12
        return np.pi * r * r * height, np.array([side, side, r * r / 2])
    if kind == "ellipsoid":
        a, b, c = size
        return 4 / 3 * np.pi * a * b * c, np.array([b * b + c * c, a * a + c * c,
                                                    a * a + b * b]) / 5
    if kind == "box":
        a, b, c = size
        return 8 * a * b * c, np.array([b * b + c * c, a * a + c * c, a * a + b * b]) / 3
    return None


def geom_mass(reader: Reader, element: Element, attrib: dict[str, str], kind: str,
              size: np.ndarray, at: Frame, path: str) -> Mass | None:
    """A geom's mass properties in the body frame, None when it has none casmech computes."""
    if kind == "plane":
        return None
    solid = _solid(kind, size)
    if solid is None:
        reader.warn(element, path, f"the mass of a {kind} geom is not computed (casmech does "
                    "not read mesh volumes): the body's mass leaves it out", code="E101",
                    hint="give the body an <inertial>")
        return None
    volume, per_mass = solid
    mass = reader.number(element, attrib, "mass", path)
    if mass is None:
        mass = reader.number(element, attrib, "density", path, 1000.0) * volume
    if mass < 0:
        raise reader.error(element, f"{path}.mass", "the geom's mass is negative",
                           "a mass >= 0", code="E400", got=f"{mass:g}")
    if attrib.get("shellinertia", "false") == "true":
        reader.warn(element, path, "shellinertia not translated: the geom is a solid",
                    code="E101")
    return Mass(mass, np.zeros(3), np.diag(mass * per_mass)).placed(at)
