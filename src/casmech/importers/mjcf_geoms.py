"""MJCF geoms -> casmech `geometry` items and contact force elements.

Pictures: the geoms MuJoCo shows by default (groups 0, 1 and 2) become geometry items in the
body frame: sphere, box (full sizes), cylinder (length = twice the half-length, along z),
capsule (drawn as its cylinder; casmech's contacts collide a cylinder item as the capsule
around its axis) and mesh (the `<mesh>` asset's file, found in `meshdir` or `--mesh-dir`, with
its `scale` per axis). Ellipsoids, height fields and SDFs are not drawn (a warning).

Contacts (unless `<option><flag contact="disable"/>`): every plane geom of the world (or of a
body welded to it) against each sphere, capsule, cylinder (as a capsule) and box (its eight
corners) of a moving body whose contype/conaffinity bits meet the plane's, not excluded by
`<contact><exclude>`: `sphere_plane`, `capsule_plane` and `points_plane` elements
(docs/forces.md). MuJoCo's contact is a soft constraint solved each step, which no force law
reproduces; the approximation is casmech's linear law whose mass-spring-damper on the body's
mass m has MuJoCo's time constant and damping ratio (`solref` = tc, zeta: stiffness m/(tc zeta)^2,
damping 2 m / tc; a negative solref gives stiffness and damping per unit mass directly) and
friction the larger of the two geoms' sliding coefficients (condim 1: none; torsional and
rolling friction are not translated). `<contact><pair>` is not translated (a warning).
"""

from __future__ import annotations

import numpy as np

from casmech.core.quaternions import from_matrix
from casmech.importers.adm_frames import tidy
from casmech.importers.mesh_paths import MeshPaths
from casmech.importers.mjcf_bodies import Body, Geom
from casmech.importers.mjcf_frames import Frame
from casmech.importers.mjcf_read import Reader

VISIBLE = range(0, 3)  # geom groups MuJoCo's viewer shows by default
SOLREF = (0.02, 1.0)  # MuJoCo's default time constant [s] and damping ratio


def _item(reader: Reader, geom: Geom, meshes: MeshPaths, assets: dict, path: str
          ) -> dict | None:
    kind, size = geom.kind, geom.size
    if kind == "sphere":
        return {"sphere": float(size[0])}
    if kind == "box":
        return {"box": tidy(2 * size)}
    if kind in ("cylinder", "capsule"):
        return {"cylinder": {"radius": float(size[0]), "length": float(2 * size[1]),
                             "axis": "z"}}
    if kind == "mesh":
        name = geom.attrib.get("mesh")
        if name not in assets:
            raise reader.error(geom.element, f"{path}.mesh", f"unknown mesh '{name}'",
                               "the name of a <mesh> asset", code="E300", got=str(name))
        file, scale, base = assets[name]
        if file is None:
            reader.warn(geom.element, path, f"mesh '{name}' has no file (vertices in the XML):"
                        " not drawn", code="E103")
            return None
        written, found = meshes.written(file, base)
        if not found:
            reader.warn(geom.element, path, f"mesh file '{file}' not found; written as "
                        f"'{written}'", code="E305", hint="give its folder with --mesh-dir DIR")
        item = {"mesh": written}
        if np.any(scale != 1):
            item["scale"] = float(scale[0]) if np.all(scale == scale[0]) and scale[0] > 0 \
                else tidy(scale)
        return item
    if kind != "plane":
        reader.warn(geom.element, path, f"a {kind} geom is not drawn (casmech draws boxes, "
                    "cylinders, spheres and meshes)", code="E103")
    return None


def geometry_items(reader: Reader, members: list[tuple[Body, Frame]], centre: np.ndarray,
                   meshes: MeshPaths, assets: dict) -> list[dict]:
    """The visible geoms of a casmech body's MJCF bodies, in the body frame (origin at the
    centre of mass `centre`, given with the members' frames in the head body's frame)."""
    items = []
    for body, at in members:
        for geom in body.geoms:
            group = int(float(geom.attrib.get("group", "0")))
            if group not in VISIBLE:
                continue
            item = _item(reader, geom, meshes, assets, f"body[{body.name}].geom[{geom.name}]")
            if item is None:
                continue
            placed = at * geom.at
            offset = placed.origin - centre
            if np.any(offset):
                item["offset"] = tidy(offset, max(1.0, float(np.max(np.abs(centre)))))
            if not np.allclose(placed.rotation, np.eye(3), rtol=0, atol=1e-15):
                item["orientation"] = {"euler_parameters": tidy(from_matrix(placed.rotation))}
            items.append(item)
    return items


def _bits(geom: Geom, key: str) -> int:
    return int(float(geom.attrib.get(key, "1")))


def _law(reader: Reader, plane: Geom, geom: Geom, mass: float, path: str) -> dict:
    solrefs = [reader.numbers(g.element, g.attrib, "solref", path, (2,), SOLREF)
               for g in (plane, geom)]
    tc, zeta = (solrefs[0] + solrefs[1]) / 2  # MuJoCo's mix with equal solmix
    if tc < 0:
        return {"law": "linear", "stiffness": -tc * mass, "damping": -zeta * mass}
    return {"law": "linear", "stiffness": mass / (tc * zeta) ** 2, "damping": 2 * mass / tc}


def contacts(reader: Reader, planes: list[tuple[Geom, Frame, str]],
             moving: list[tuple[str, float, Body, Geom, Frame]], excluded: set,
             path: str = "contact") -> list[tuple[dict, str]]:
    """(force element, comment) per plane and colliding geom of a moving body; `moving` holds
    (casmech body, its mass, MJCF body, geom, the geom's global frame); `planes` (geom, its
    global frame, its MJCF body's name)."""
    found = []
    for plane, plane_at, plane_body in planes:
        normal, at = plane_at.rotation[:, 2], plane_at.origin
        for body_name, mass, body, geom, geom_at in moving:
            if geom.kind not in ("sphere", "capsule", "cylinder", "box"):
                continue
            if not (_bits(plane, "contype") & _bits(geom, "conaffinity")
                    or _bits(geom, "contype") & _bits(plane, "conaffinity")):
                continue
            if (plane_body, body.name) in excluded:
                continue
            element = {"name": f"{geom.name}_{plane.name}", "body_i": "ground",
                       "body_j": body_name, "plane": {"at": tidy(at), "normal": tidy(normal)}}
            size, centre, axis = geom.size, geom_at.origin, geom_at.rotation[:, 2]
            if geom.kind == "sphere":
                element |= {"type": "sphere_plane", "radius": float(size[0]),
                            "center": tidy(centre)}
            elif geom.kind in ("capsule", "cylinder"):
                element |= {"type": "capsule_plane", "radius": float(size[0]),
                            "ends": [tidy(centre - size[1] * axis),
                                     tidy(centre + size[1] * axis)]}
            else:
                corners = [geom_at.point(np.array([sx, sy, sz]) * size)
                           for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
                element |= {"type": "points_plane", "points": [tidy(c) for c in corners]}
            element["normal"] = _law(reader, plane, geom, mass, path)
            condim = int(float(geom.attrib.get("condim", "3")))
            if condim > 1:
                mu = max(float(g.attrib.get("friction", "1").split()[0]) for g in (plane, geom))
                element["friction"] = {"static": mu, "dynamic": mu}
            if condim > 3:
                reader.warn(geom.element, path, f"condim {condim}: torsional and rolling "
                            "friction not translated")
            comment = (f"contact of geom {geom.name} (line {geom.element.line}) with plane "
                       f"{plane.name} (line {plane.element.line}); "
                       + ("a cylinder collides as its capsule; " if geom.kind == "cylinder"
                          else "") + "law approximated from solref (docs/import.md)")
            found.append((element, comment))
    return found
