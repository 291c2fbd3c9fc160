"""MJCF `<actuator>` elements -> effort motors of casmech joints.

An actuator on a joint that became a single casmech revolute or translational joint is the
joint's effort motor, exactly MuJoCo's force law with constant controls:

    L = gear (q0 + angle),  L_dot = gear angle_dot          (q0: the joint's qpos at t = 0)
    force = gain ctrl + bias0 + bias1 L + bias2 L_dot        (clamped to forcerange if limited)
    torque (or force) on the joint = gear force

`motor` (gain 1, no bias), `position` (kp, kv: gain kp, bias 0, -kp, -kv), `velocity` (kv: gain
kv, bias 0, 0, -kv) and `general` with fixed gain, affine or no bias and no activation
dynamics. The control is a parameter `ctrl_<actuator>` (the keyframe's ctrl, else 0, clamped to
ctrlrange when limited), so `--set ctrl_shoulder=0.3` sets it. Two actuators on one joint add.
The angle is casmech's (in (-pi, pi], measured from the pose in the file), so a position servo
sees q0 + angle, which wraps once the joint turns past pi from its initial value.
Not translated (a warning naming the line): other actuator types (`intvelocity`, `damper`,
`cylinder`, `muscle`, `adhesion`, `plugin`), activation dynamics, gain or bias types other than
fixed and affine, and transmissions other than a joint (tendons, sites, bodies) or joints that
were merged into a composite casmech joint.
"""

from __future__ import annotations

import numpy as np

from casmech.core.records import record
from casmech.importers.mjcf_defaults import Defaults
from casmech.importers.mjcf_read import Element, Reader

SHORTCUTS = ("motor", "position", "velocity", "general")
OTHERS = ("intvelocity", "damper", "cylinder", "muscle", "adhesion", "plugin")
TRANSMISSIONS = ("joint", "jointinparent", "tendon", "site", "body", "cranksite")


@record(frozen=False)
class Actuator:
    name: str
    element: Element
    joint: str
    gear: float
    gain: float
    bias: tuple[float, float, float]
    ctrl: float
    force_range: tuple[float, float] | None
    note: str  # what the control was (range, clamping)


def _limited(reader: Reader, element: Element, attrib: dict, key: str, autolimits: bool
             ) -> tuple[float, float] | None:
    values = reader.numbers(element, attrib, f"{key}range", "actuator", (2,))
    flag = attrib.get(f"{key}limited", "auto")
    if flag == "true" or (flag == "auto" and autolimits and values is not None):
        if values is None:
            raise reader.error(element, f"actuator.{key}range", f"{key}limited without a "
                               f"{key}range", f'{key}range="lower upper"', code="E100")
        return float(values[0]), float(values[1])
    return None


def _law(reader: Reader, element: Element, attrib: dict, path: str):
    """(gain, bias) of a shortcut's force law, or None (warned) when it is not translated."""
    tag = element.tag
    if tag == "motor":
        return 1.0, (0.0, 0.0, 0.0)
    if tag == "position":
        kp = reader.number(element, attrib, "kp", path, 1.0)
        kv = reader.number(element, attrib, "kv", path, 0.0)
        return kp, (0.0, -kp, -kv)
    if tag == "velocity":
        kv = reader.number(element, attrib, "kv", path, 1.0)
        return kv, (0.0, 0.0, -kv)
    for key, allowed in (("dyntype", ("none",)), ("gaintype", ("fixed",)),
                         ("biastype", ("none", "affine"))):
        if attrib.get(key, allowed[0]) not in allowed:
            reader.warn(element, path, f"{key}=\"{attrib[key]}\" not translated: the actuator "
                        "is not translated", hint=f"casmech translates {key} "
                        + " or ".join(allowed))
            return None
    gain = reader.numbers(element, attrib, "gainprm", path, tuple(range(1, 11)), (1.0,))
    bias = reader.numbers(element, attrib, "biasprm", path, tuple(range(1, 11)), (0.0,))
    bias = np.concatenate([bias, np.zeros(3)])[:3] if attrib.get("biastype") == "affine" \
        else np.zeros(3)
    return float(gain[0]), tuple(float(b) for b in bias)


def actuators(reader: Reader, defaults: Defaults, autolimits: bool, ctrl: np.ndarray | None
              ) -> list[Actuator]:
    """Every translatable actuator, in file order (the others are warnings)."""
    found = []
    elements = [e for block in reader.root.findall("actuator") for e in block.children]
    for index, element in enumerate(elements):
        path = f"actuator[{element.attrib.get('name', index)}]"
        if element.tag in OTHERS or element.tag not in SHORTCUTS:
            reader.warn(element, path, f"<{element.tag}> actuator not translated",
                        hint="casmech translates motor, position, velocity and general "
                        "actuators on joints")
            continue
        attrib = defaults.attributes(element, None, path)
        target = [key for key in TRANSMISSIONS if key in attrib]
        if target != ["joint"]:
            reader.warn(element, path, f"an actuator on a {target[0] if target else 'nothing'}"
                        " not translated (casmech translates actuators on joints)")
            continue
        law = _law(reader, element, attrib, path)
        if law is None:
            continue
        gear = reader.numbers(element, attrib, "gear", path, tuple(range(1, 7)), (1.0,))
        value = float(ctrl[index]) if ctrl is not None else 0.0
        note = f"ctrl {value:g}" + (" (the keyframe's)" if ctrl is not None else "")
        limits = _limited(reader, element, attrib, "ctrl", autolimits)
        if limits is not None:
            note += f", range [{limits[0]:g}, {limits[1]:g}]"
            if not limits[0] <= value <= limits[1]:
                value = float(np.clip(value, *limits))
                note += f", clamped to {value:g}"
        found.append(Actuator(element.attrib.get("name", f"actuator{index + 1}"), element,
                              attrib["joint"], float(gear[0]), law[0], law[1], value,
                              _limited(reader, element, attrib, "force", autolimits), note))
    return found


def expression(actuator: Actuator, parameter: str, q0: float, rate: str, coordinate: str
               ) -> str:
    """The effort motor's value: gear times the (clamped) actuator force."""
    gear, (b0, b1, b2) = actuator.gear, actuator.bias
    terms = [f"{actuator.gain!r}*{parameter}"] if actuator.gain else []
    if b0:
        terms.append(repr(b0))
    if b1:
        terms.append(f"{b1!r}*{gear!r}*({q0!r} + {coordinate})")
    if b2:
        terms.append(f"{b2!r}*{gear!r}*{rate}")
    force = " + ".join(terms) or "0"
    if actuator.force_range is not None:
        low, high = actuator.force_range
        force = f"min(max({force}, {low!r}), {high!r})"
    return f"{gear!r}*({force})"
