"""URDF `visual` elements -> casmech `geometry` items (pictures only).

Each item is placed in the body frame: the link's axes, origin at the body's centre of mass.
URDF cylinders lie along their z axis (casmech's default cylinder axis). Mesh files are looked
for (`package://`, `file://`, relative names, `--mesh-dir`: importers/mesh_paths.py) and named
as the YAML can read them; a mesh's `scale` is kept per axis, signs included (a mirrored mesh).
"""

from __future__ import annotations

import numpy as np

from casmech.core.quaternions import from_matrix
from casmech.importers.adm_frames import tidy
from casmech.importers.mesh_paths import MeshPaths
from casmech.importers.urdf_read import Element, Reader
from casmech.importers.urdf_tree import Frame, Link, frame


def _box(reader: Reader, element: Element, path: str, meshes: MeshPaths) -> dict:
    return {"box": tidy(reader.numbers(element, path, "size", 3))}


def _cylinder(reader: Reader, element: Element, path: str, meshes: MeshPaths) -> dict:
    return {"cylinder": {"radius": reader.number(element, path, "radius"),
                         "length": reader.number(element, path, "length"), "axis": "z"}}


def _sphere(reader: Reader, element: Element, path: str, meshes: MeshPaths) -> dict:
    return {"sphere": reader.number(element, path, "radius")}


def mesh_scale(scale: np.ndarray) -> float | list[float] | None:
    """A mesh scale as written: none for 1, one number when uniform and positive, else the
    three factors (docs/format.md: a vector keeps a mirror's signs)."""
    if np.all(scale == 1):
        return None
    if np.all(scale == scale[0]) and scale[0] > 0:
        return float(scale[0])
    return tidy(scale)


def _mesh(reader: Reader, element: Element, path: str, meshes: MeshPaths) -> dict:
    name = reader.text(element, path, "filename")
    written, found = meshes.written(name)
    if not found and name.startswith("file://"):
        reader.warn(element, path, f"mesh '{name}' not found: not translated", code="E305",
                    hint="give the folder holding the meshes with --mesh-dir DIR")
        return {}
    if not found:
        reader.warn(element, path, f"mesh '{name}' not found; written as '{written}'",
                    code="E305", hint="give the folder holding the meshes (or the ROS "
                    "packages) with --mesh-dir DIR")
    item = {"mesh": written}
    scale = reader.numbers(element, path, "scale", 3, (1.0, 1.0, 1.0))
    if np.any(scale == 0):
        reader.warn(element, path, f"mesh scale {scale.tolist()} has a zero factor: the mesh is "
                    "not translated", code="E410")
        return {}
    if mesh_scale(scale) is not None:
        item["scale"] = mesh_scale(scale)
    return item


SHAPES = {"box": _box, "cylinder": _cylinder, "sphere": _sphere, "mesh": _mesh}


def geometry_items(reader: Reader, members: list[tuple[Link, Frame]], centre,
                   meshes: MeshPaths) -> list[dict]:
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
            item = SHAPES[kinds[0].tag](reader, kinds[0], f"{path}.geometry.{kinds[0].tag}",
                                        meshes)
            if not item:
                continue
            placed = at * frame(reader, visual.find("origin"), f"{path}.origin")
            offset = placed.origin - centre
            if np.any(offset):
                item["offset"] = tidy(offset, max(1.0, np.max(np.abs(centre))))
            if not np.allclose(placed.rotation, np.eye(3), rtol=0, atol=1e-15):
                item["orientation"] = {"euler_parameters":
                                       tidy(from_matrix(placed.rotation))}
            items.append(item)
    return items
