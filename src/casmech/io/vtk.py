"""A Scene as a ParaView time series: one .vtu per frame (meshio) and a .pvd collection.

Every frame holds the same cells in the same order: each part's triangles, then one line per
link. Cell data: `body` (index of the body a cell moves with, in file order; -1 ground) and
`joint` (index of the joint a marker belongs to, in file order; -1 for body geometry). The .pvd
names the bodies and joints behind those indices in a comment, and its `timestep` attributes are
the simulated times, so ParaView's time controls show seconds.
"""

from __future__ import annotations

import os
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from casmech.io.animate import Scene, meshio_module

FRAMES = "frames"  # sub-directory of the .vtu files, next to the .pvd


def frame_geometry(scene: Scene):
    """Global points of every frame (F, n, 3), the cell blocks and the cell data."""
    rotations = scene.rotations()
    points, triangles, body, joint, start = [], [], [], [], 0
    for part in scene.parts:
        points.append(scene.place(part.body, part.points, rotations))
        triangles.append(part.triangles + start)
        body += [part.body] * len(part.triangles)
        joint += [part.joint] * len(part.triangles)
        start += len(part.points)
    lines = []
    for link in scene.links:
        points.append(scene.place(link.body_a, link.point_a[None], rotations))
        points.append(scene.place(link.body_b, link.point_b[None], rotations))
        lines.append([start, start + 1])
        start += 2
    cells = [("triangle", np.vstack(triangles).astype(np.int64))]
    data = {"body": [np.array(body, np.int32)], "joint": [np.array(joint, np.int32)]}
    if lines:
        cells.append(("line", np.array(lines, np.int64)))
        data["body"].append(np.array([link.body_a for link in scene.links], np.int32))
        data["joint"].append(np.array([link.joint for link in scene.links], np.int32))
    return np.concatenate(points, axis=1), cells, data


def legend(scene: Scene) -> str:
    bodies = ", ".join(f"{k}={name}" for k, name in enumerate(scene.bodies))
    joints = ", ".join(f"{k}={name}" for k, name in enumerate(scene.joints))
    return f"cell data body: -1=ground, {bodies}; cell data joint: -1=none, {joints}"


def write_vtk(scene: Scene, directory: str | Path) -> Path:
    """Write DIR/frames/frame_NNNNN.vtu and DIR/animation.pvd; return the .pvd's path."""
    meshio = meshio_module()
    directory = Path(directory)
    (directory / FRAMES).mkdir(parents=True, exist_ok=True)
    for stale in (directory / FRAMES).glob("frame_*.vtu"):  # a longer earlier run's frames
        stale.unlink()
    points, cells, data = frame_geometry(scene)
    entries = []
    for k, t in enumerate(scene.times):
        name = f"{FRAMES}/frame_{k:05d}.vtu"
        meshio.Mesh(points[k], cells, cell_data=data).write(directory / name)
        entries.append(f'    <DataSet timestep="{float(t)!r}" part="0" file={quoteattr(name)}/>')
    pvd = directory / "animation.pvd"
    temporary = pvd.with_name(pvd.name + ".tmp")
    temporary.write_text(
        '<?xml version="1.0"?>\n'
        f"<!-- casmech animation of {escape(scene.name).replace('--', '- -')}: "
        f"{escape(legend(scene)).replace('--', '- -')} -->\n"
        '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
        "  <Collection>\n" + "\n".join(entries) + "\n  </Collection>\n</VTKFile>\n")
    os.replace(temporary, pvd)
    return pvd
