"""MJCF `<equality>` elements -> closed loops (casmech joints).

- `connect` (body1, body2, anchor in body1's frame; or site1, site2) -> a `spherical` joint at
  the anchor: MuJoCo takes the constraint as satisfied at qpos0, casmech at the pose written;
- `weld` (body1, body2; or site1, site2) -> a `fixed` joint at body2's anchor (the weld's
  relative pose is the one at the initial pose; a `relpose` that differs from it is a
  warning); `torquescale` is not translated;
- `joint` (a polynomial coupling of two joints' coordinates), `tendon` and `flex` are not
  translated: a warning naming the line, kept as a comment (casmech has no rows over two
  joints' coordinates yet).

MuJoCo's equality constraints are soft (solref, solimp); casmech's joints hold exactly, which is
MuJoCo's behaviour in the limit of stiff constraints. `active="false"` ones are left out (a
warning).
"""

from __future__ import annotations

import numpy as np

from casmech.core.records import record
from casmech.importers.mjcf_bodies import Body
from casmech.importers.mjcf_frames import Frame
from casmech.importers.mjcf_read import Element, Reader

KINDS = {"connect": "spherical", "weld": "fixed"}


@record(frozen=False)
class Loop:
    name: str
    element: Element
    kind: str  # casmech joint type
    body_i: Body  # MJCF bodies (body2, body1)
    body_j: Body
    at: np.ndarray  # global


def _ends(reader: Reader, element: Element, bodies: dict[str, Body], sites: dict, path: str):
    """(body1, body2, anchor of body1 or site1 frame, site2 frame) of an equality element."""
    attrib = element.attrib
    if "site1" in attrib or "site2" in attrib:
        ends = []
        for key in ("site1", "site2"):
            name = attrib.get(key)
            if name not in sites:
                raise reader.error(element, f"{path}.{key}", f"unknown site '{name}'",
                                   "the name of a <site>", code="E300", got=str(name))
            ends.append(sites[name])
        return ends[0][0], ends[1][0], ends[0][1], ends[1][1]
    found = []
    for key, default in (("body1", None), ("body2", "world")):
        name = attrib.get(key, default)
        if name is None:
            raise reader.error(element, path, f"<{element.tag}> has no '{key}'",
                               f'{key}="body name"', code="E100")
        if name not in bodies:
            from casmech.errors import did_you_mean

            raise reader.error(element, f"{path}.{key}", f"unknown body '{name}'",
                               "the name of a <body>", code="E300", got=name,
                               hint=did_you_mean(name, bodies) or None)
        found.append(bodies[name])
    return found[0], found[1], None, None


def loops(reader: Reader, bodies: dict[str, Body], sites: dict[str, tuple[Body, Frame]],
          frames: dict[Body, Frame], trailer: list[str]) -> list[Loop]:
    """The connect and weld constraints as loops; the others warned and noted in `trailer`."""
    found = []
    elements = [e for block in reader.root.findall("equality") for e in block.children]
    for index, element in enumerate(elements):
        name = element.attrib.get("name", f"{element.tag}{index + 1}")
        path = f"equality[{name}]"
        if element.tag not in KINDS:
            what = {"joint": "a coupling of two joints' coordinates (rows over two joints' "
                             "coordinates do not exist in casmech yet)"}.get(element.tag,
                                                                              "not translated")
            reader.warn(element, path, f"<{element.tag}> equality not translated: {what}",
                        hint="write the coupling by hand, or leave the joints free")
            trailer.append(f"equality {element.tag} {name} (line {element.line} of "
                           f"{element.file}) not translated: {what}")
            continue
        if element.attrib.get("active", "true") == "false":
            reader.warn(element, path, "an inactive equality constraint is left out")
            trailer.append(f"inactive equality {name} (line {element.line}) left out")
            continue
        body1, body2, anchor1, _ = _ends(reader, element, bodies, sites, path)
        if element.tag == "connect":
            at = frames[body1].point(anchor1.origin) if anchor1 is not None else \
                frames[body1].point(reader.numbers(element, element.attrib, "anchor", path,
                                                   (3,), (0.0, 0.0, 0.0)))
        else:
            at = frames[body2].point(reader.numbers(element, element.attrib, "anchor", path,
                                                    (3,), (0.0, 0.0, 0.0))) \
                if anchor1 is None else frames[body1].point(anchor1.origin)
            _check_weld(reader, element, frames[body1], frames[body2], path)
        found.append(Loop(name, element, KINDS[element.tag], body2, body1, at))
    return found


def _check_weld(reader: Reader, element: Element, one: Frame, two: Frame, path: str) -> None:
    relpose = reader.numbers(element, element.attrib, "relpose", path, (7,))
    if element.attrib.get("torquescale") not in (None, "1", "1.0"):
        reader.warn(element, f"{path}.torquescale", "torquescale not translated")
    if relpose is None or not np.any(relpose[3:]):
        return  # MuJoCo: the relative pose at qpos0
    from casmech.importers.mjcf_frames import quaternion_matrix

    rotation = two.rotation.T @ one.rotation
    offset = two.rotation.T @ (one.origin - two.origin)
    if not (np.allclose(rotation, quaternion_matrix(relpose[3:]), atol=1e-9)
            and np.allclose(offset, relpose[:3], atol=1e-9)):
        reader.warn(element, f"{path}.relpose", "relpose differs from the relative pose at the "
                    "initial pose: casmech's fixed joint keeps the initial one",
                    hint="place the bodies in the file where the weld holds")
