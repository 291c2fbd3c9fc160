"""URDF `<mimic joint="A" multiplier="m" offset="o"/>` on joint B -> a casmech coupler.

URDF's relation is q_B = m q_A + o between the joints' values. casmech's joint coordinates s are
measured from the imported pose (the values `positions`, q = q0 + s), so the coupler is
`joints: [B, A], coefficients: [1, -m], offset: m q0_A + o - q0_B` (docs/format.md, couplings;
MuJoCo's URDF import writes the same relation as a joint equality). A mimic of a joint that is
no joint of the model (merged into a chain through massless links, or locked) is a warning.
"""

from __future__ import annotations

from casmech.errors import did_you_mean
from casmech.importers.adm_frames import tidy
from casmech.importers.emit import Item


def coupler(reader, names, joints: dict[str, str], positions: dict[str, float], joint,
            element, known) -> Item | None:
    """The coupler of joint `joint`'s <mimic> `element` (joints: URDF joint -> casmech joint
    name of the single joints written; known: every URDF joint's name), or None after a
    warning."""
    path = f"joint[{joint.name}].mimic"
    target = reader.text(element, path, "joint")
    if target not in known:
        reader.warn(element, path, f"mimic not translated: the URDF has no joint '{target}'",
                    hint=did_you_mean(target, known))
        return None
    if target not in joints or joint.name not in joints:
        missing = target if target not in joints else joint.name
        reader.warn(element, path, f"mimic not translated: '{missing}' is not a joint of the "
                    "model (merged with others through massless links, or locked)",
                    hint="write the coupling by hand as a coupler (docs/format.md)")
        return None
    multiplier = reader.number(element, path, "multiplier", 1.0)
    offset = reader.number(element, path, "offset", 0.0)
    shift = multiplier * positions.get(target, 0.0) + offset - positions.get(joint.name, 0.0)
    data = {"name": names(f"{joints[joint.name]}_mimic", "_joint"), "type": "coupler",
            "joints": [joints[joint.name], joints[target]],
            "coefficients": tidy([1.0, -multiplier], 1.0)}
    if shift:
        data["offset"] = tidy([shift], 1.0)[0]
    comment = (f"URDF mimic (line {element.line}): {joint.name} = {multiplier:g} {target}"
               + (f" + {offset:g}" if offset else ""))
    return Item(data, [comment])
