"""URDF `visual` elements -> casmech `geometry` items (pictures only).

Each item is placed in the body frame: the link's axes, origin at the body's centre of mass.
URDF cylinders lie along their z axis (casmech's default cylinder axis). Mesh file names: a
`package://PKG/` prefix is dropped (the path is then relative to the package's root: write the
YAML there), a `file://` prefix too; a warning says so.
"""

from __future__ import annotations

import numpy as np

from casmech.core.quaternions import from_matrix
from casmech.importers.adm_frames import tidy
from casmech.importers.urdf_read import Element, Reader
from casmech.importers.urdf_tree import Frame, Link, frame


def _box(reader: Reader, element: Element, path: str) -> dict:
    return {"box": tidy(reader.numbers(element, path, "size", 3))}


def _cylinder(reader: Reader, element: Element, path: str) -> dict:
    return {"cylinder": {"radius": reader.number(element, path, "radius"),
                         "length": reader.number(element, path, "length"), "axis": "z"}}


def _sphere(reader: Reader, element: Element, path: str) -> dict:
    return {"sphere": reader.number(element, path, "radius")}


def _mesh(reader: Reader, element: Element, path: str) -> dict:
    name = reader.text(element, path, "filename")
    for prefix, note in (("package://", "relative to the ROS package's root: write the YAML "
                                        "there, or copy the meshes beside it"),
                         ("file://", "a local file")):
        if name.startswith(prefix):
            rest = name[len(prefix):]
            name = rest.split("/", 1)[1] if prefix == "package://" and "/" in rest else rest
            reader.warn(element, path, f"mesh '{element.attrib['filename']}' written as "
                        f"'{name}' ({note})", code="E103")
    item = {"mesh": name}
    scale = reader.numbers(element, path, "scale", 3, (1.0, 1.0, 1.0))
    if not np.allclose(scale, scale[0], rtol=1e-12, atol=0):
        reader.warn(element, path, f"non-uniform mesh scale {scale.tolist()}: casmech scales "
                    "meshes uniformly; the mean is used", code="E103")
    if np.mean(scale) != 1:
        item["scale"] = float(np.mean(scale))
    return item


SHAPES = {"box": _box, "cylinder": _cylinder, "sphere": _sphere, "mesh": _mesh}


def geometry_items(reader: Reader, members: list[tuple[Link, Frame]], centre) -> list[dict]:
    """The visuals of a body's links, placed in the body frame whose origin is `centre`."""
    items = []
    for link, at in members:
        for k, visual in enumerate(link.visuals):
            path = f"link[{link.name}].visual[{k}]"
            shape = visual.find("geometry")
            kinds = [c for c in shape.children if c.tag in SHAPES] if shape is not None else []
            if len(kinds) != 1:
                reader.warn(shape or visual, path, "a visual's <geometry> needs one of "
                            f"{', '.join(SHAPES)}: not translated", code="E103")
                continue
            item = SHAPES[kinds[0].tag](reader, kinds[0], f"{path}.geometry.{kinds[0].tag}")
            placed = at * frame(reader, visual.find("origin"), f"{path}.origin")
            offset = placed.origin - centre
            if np.any(offset):
                item["offset"] = tidy(offset, max(1.0, np.max(np.abs(centre))))
            if not np.allclose(placed.rotation, np.eye(3), rtol=0, atol=1e-15):
                item["orientation"] = {"euler_parameters":
                                       tidy(from_matrix(placed.rotation))}
            items.append(item)
    return items
