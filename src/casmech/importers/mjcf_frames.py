"""MJCF positions and orientations -> frames (importers/urdf_tree.Frame: rotation, origin).

An element's orientation is one of `quat` (w x y z, normalised), `axisangle` (axis, angle in
the compiler's unit), `euler` (three angles about the axes of `eulerseq`), `xyaxes` (x axis,
then y made orthogonal to it), `zaxis` (the shortest rotation taking z there) or, for geoms
and sites, `fromto` (the z axis from the first point to the second, at their midpoint); two of
them on one element is an error, as in MuJoCo.
"""

from __future__ import annotations

import numpy as np

from casmech.importers.mjcf_defaults import Compiler
from casmech.importers.mjcf_read import Element, Reader
from casmech.importers.urdf_tree import IDENTITY, Frame, axis_rotation

FORMS = ("quat", "axisangle", "euler", "xyaxes", "zaxis")
AXES = {"x": 0, "y": 1, "z": 2}


def quaternion_matrix(q) -> np.ndarray:
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def z_to(direction: np.ndarray) -> np.ndarray:
    """The shortest rotation taking the z axis to `direction` (MuJoCo's mju_quatZ2Vec)."""
    z = direction / np.linalg.norm(direction)
    axis = np.cross([0.0, 0.0, 1.0], z)
    sine = np.linalg.norm(axis)
    if sine < 1e-10:
        return np.eye(3) if z[2] > 0 else np.diag([1.0, -1.0, -1.0])  # pi about x
    return axis_rotation(axis / sine, np.arctan2(sine, z[2]))


def euler_matrix(angles, sequence: str) -> np.ndarray:
    rotation = np.eye(3)
    for angle, axis in zip(angles, sequence, strict=True):
        step = axis_rotation(np.eye(3)[AXES[axis.lower()]], angle)
        rotation = rotation @ step if axis.islower() else step @ rotation
    return rotation


def rotation(reader: Reader, element: Element, attrib: dict[str, str], path: str,
             compiler: Compiler) -> np.ndarray:
    """The rotation an element's orientation attributes give (identity when none)."""
    given = [form for form in FORMS if form in attrib]
    if len(given) > 1:
        raise reader.error(element, path, f"<{element.tag}> has two orientations "
                           f"({', '.join(given)})", "one of " + ", ".join(FORMS),
                           code="E407")
    if not given:
        return np.eye(3)
    form = given[0]
    sizes = {"quat": 4, "axisangle": 4, "euler": 3, "xyaxes": 6, "zaxis": 3}
    values = reader.numbers(element, attrib, form, path, (sizes[form],))
    if form == "quat":
        if not np.any(values):
            raise reader.error(element, f"{path}.quat", "the quaternion is zero",
                               "w x y z, not all zero", code="E403")
        return quaternion_matrix(values)
    if form == "euler":
        return euler_matrix([compiler.angle(v) for v in values], compiler.eulerseq)
    vectors = {"axisangle": values[:3], "xyaxes": values[:3], "zaxis": values}[form]
    if np.linalg.norm(vectors) < 1e-12:
        raise reader.error(element, f"{path}.{form}", f"the {form} axis is zero",
                           "a non-zero direction", code="E404")
    if form == "axisangle":
        return axis_rotation(values[:3] / np.linalg.norm(values[:3]), compiler.angle(values[3]))
    if form == "zaxis":
        return z_to(values)
    x = values[:3] / np.linalg.norm(values[:3])
    y = values[3:] - (values[3:] @ x) * x
    if np.linalg.norm(y) < 1e-12:
        raise reader.error(element, f"{path}.xyaxes", "the x and y axes are parallel",
                           "two independent directions", code="E405")
    y /= np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def frame(reader: Reader, element: Element, attrib: dict[str, str], path: str,
          compiler: Compiler) -> Frame:
    """The frame of `pos` and the orientation attributes (in the parent's frame)."""
    position = reader.numbers(element, attrib, "pos", path, (3,), (0.0, 0.0, 0.0))
    return Frame(rotation(reader, element, attrib, path, compiler), position)


def fromto(reader: Reader, element: Element, attrib: dict[str, str], path: str
           ) -> tuple[Frame, float] | None:
    """The frame and half length of a `fromto` (z along it, at its midpoint), or None."""
    values = reader.numbers(element, attrib, "fromto", path, (6,))
    if values is None:
        return None
    start, end = values[:3], values[3:]
    length = np.linalg.norm(end - start)
    if length < 1e-12:
        raise reader.error(element, f"{path}.fromto", "the two points of fromto coincide",
                           "two distinct points", code="E404")
    return Frame(z_to(end - start), (start + end) / 2), length / 2


__all__ = ["IDENTITY", "Frame", "frame", "fromto", "rotation", "quaternion_matrix"]
