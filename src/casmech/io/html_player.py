"""A Scene as one self-contained HTML file that plays the motion offline.

The page is player/player.html with player/player.css, player/three.min.js (three.js, bundled by
player/vendor/build.sh; MIT licence in player/three.LICENSE), player/player.js (the player on
three.js) and the scene with its overlays (overlays.py) as JSON inlined: no network request of
any kind (its Content-Security-Policy forbids them). The JSON holds each part's body-frame
points and triangles once, and per frame the CM position and Euler parameters of every body and
the overlays' vectors, so the file grows with frames x (bodies + vectors), not with frames x
triangles.
"""

from __future__ import annotations

import html
import json
import os
import re
from importlib import resources
from pathlib import Path

import numpy as np

from casmech.core.version import VERSION
from casmech.io.animate import Scene
from casmech.io.overlays import UNITS, Overlays

DIGITS = 7  # significant digits of coordinates and Euler parameters in the page
DRIFT = 1.0  # the camera follows the mechanism when its centre moves more than this x its size


def _numbers(values) -> str:
    """A JSON array of finite floats, DIGITS significant digits each."""
    return "[" + ",".join(f"{x:.{DIGITS}g}" for x in np.asarray(values, float).ravel()) + "]"


def _integers(values) -> str:
    return "[" + ",".join(str(int(x)) for x in np.asarray(values).ravel()) + "]"


def bounds(scene: Scene) -> tuple[np.ndarray, float]:
    """Centre and radius of a sphere holding every part at every frame (and the origin)."""
    rotations = scene.rotations()
    lows, highs = [np.zeros(3)], [np.zeros(3)]
    for part in scene.parts:
        centre = (part.points.max(axis=0) + part.points.min(axis=0)) / 2
        reach = float(np.linalg.norm(part.points - centre, axis=1).max())
        path = scene.place(part.body, centre[None], rotations)[:, 0]
        lows.append(path.min(axis=0) - reach)
        highs.append(path.max(axis=0) + reach)
    low, high = np.min(lows, axis=0), np.max(highs, axis=0)
    radius = float(np.linalg.norm(high - low)) / 2
    return (low + high) / 2, radius if radius > 0 else 1.0


def view_direction(scene: Scene) -> np.ndarray:
    """Where the camera starts, seen from the centre: across the plane the motion spreads least
    in (a planar mechanism faces the viewer), tilted 20 degrees up (or aside, seen from above)."""
    rotations = scene.rotations()
    frames = np.unique(np.linspace(0, len(scene.times) - 1, 12).round().astype(int))
    cloud = np.vstack([scene.place(part.body, part.points, rotations, frames).reshape(-1, 3)
                       for part in scene.parts] + [np.zeros((1, 3))])
    normal = np.linalg.eigh(np.cov(cloud.T) + 1e-12 * np.eye(3))[1][:, 0]
    normal = normal if normal @ (scene.up + [1e-3, -2e-3, 0]) >= 0 else -normal
    tilt = scene.up - (scene.up @ normal) * normal
    if np.linalg.norm(tilt) < 0.3:  # looking along up: tilt towards a horizontal direction
        tilt = np.cross([1.0, 0, 0] if abs(scene.up[0]) < 0.9 else [0, 1.0, 0], scene.up)
    view = normal + np.tan(np.radians(20)) * tilt / np.linalg.norm(tilt)
    return view / np.linalg.norm(view)


def follow(overlays: Overlays) -> str:
    """Where the camera starts: following the mechanism when its centre moves further than
    DRIFT times its smallest radius (a body falling or driving away), else free."""
    moved = np.linalg.norm(overlays.centres - overlays.centres[0], axis=1).max()
    return "mechanism" if moved > DRIFT * overlays.radii.min() else "free"


def overlays_json(overlays: Overlays) -> str:
    def items(entries, fields):
        return "[" + ",".join("{" + ",".join(f'"{key}":{value(entry)}' for key, value in
                                             fields.items()) + "}" for entry in entries) + "]"

    name = {"name": lambda x: json.dumps(x.name)}
    def origin(arrow) -> str:  # a body-fixed point once, else the path
        if arrow.carrier is None:
            return _numbers(arrow.origin)
        return f'{{"body":{arrow.carrier[0]},"point":{_numbers(arrow.carrier[1])}}}'

    arrows = items(overlays.arrows, {**name, "kind": lambda x: json.dumps(x.kind),
                                     "unit": lambda x: json.dumps(UNITS[x.kind]),
                                     "origin": origin,
                                     "vector": lambda x: _numbers(x.vector)})
    triads = items(overlays.triads, {**name, "body": lambda x: x.body,
                                     "origin": lambda x: _numbers(x.origin),
                                     "axes": lambda x: _numbers(x.axes)})
    planes = items(overlays.planes, {**name, "body": lambda x: x.body,
                                     "point": lambda x: _numbers(x.point),
                                     "normal": lambda x: _numbers(x.normal)})
    trails = items(overlays.trails, {**name, "body": lambda x: x.body,
                                     "chosen": lambda x: json.dumps(x.chosen),
                                     "points": lambda x: _numbers(x.points)})
    shapes = items(overlays.shapes, {**name, "body": lambda x: x.body,
                                     "points": lambda x: _numbers(x.points),
                                     "triangles": lambda x: _integers(x.triangles)})
    point, normal = overlays.ground
    return (f'"shapes":{shapes},"arrows":{arrows},"triads":{triads},"planes":{planes},'
            f'"trails":{trails},'
            f'"ground":{{"point":{_numbers(point)},"normal":{_numbers(normal)}}},'
            f'"centres":{_numbers(overlays.centres)},"radii":{_numbers(overlays.radii)},'
            f'"follow":{json.dumps(follow(overlays))}')


def scene_json(scene: Scene, overlays: Overlays) -> str:
    centre, radius = bounds(scene)
    parts = ",".join(
        f'{{"name":{json.dumps(part.name)},"body":{part.body},"joint":{part.joint},'
        f'"points":{_numbers(part.points)},"triangles":{_integers(part.triangles)}}}'
        for part in scene.parts)
    links = ",".join(
        f'{{"joint":{link.joint},"body_a":{link.body_a},"a":{_numbers(link.point_a)},'
        f'"body_b":{link.body_b},"b":{_numbers(link.point_b)}}}'
        for link in scene.links)
    text = (f'{{"name":{json.dumps(scene.name)},"bodies":{json.dumps(list(scene.bodies))},'
            f'"joints":{json.dumps(list(scene.joints))},"parts":[{parts}],"links":[{links}],'
            f'"times":{_numbers(scene.times)},"r":{_numbers(scene.r)},"p":{_numbers(scene.p)},'
            f'"up":{_numbers(scene.up)},"view":{_numbers(view_direction(scene))},'
            f'"center":{_numbers(centre)},"radius":{radius:.{DIGITS}g},'
            f'{overlays_json(overlays)}}}')
    return text.replace("<", "\\u003c")  # never ends or comments out the <script> element


def _asset(name: str) -> str:
    return resources.files("casmech.io").joinpath("player", name).read_text("utf-8")


def render_html(scene: Scene, overlays: Overlays) -> str:
    values = {
        "TITLE": html.escape(f"casmech: {scene.name}"),
        "VERSION": html.escape(VERSION),
        "STYLE": _asset("player.css"),
        "THREE": _asset("three.min.js"),
        "SCRIPT": _asset("player.js"),
        "DATA": scene_json(scene, overlays),
    }
    return re.sub(r"\{\{(\w+)\}\}", lambda match: values[match[1]], _asset("player.html"))


def write_html(scene: Scene, overlays: Overlays, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(path.name + ".tmp")
    temporary.write_text(render_html(scene, overlays), encoding="utf-8")
    os.replace(temporary, path)
    return path
