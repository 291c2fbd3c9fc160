"""MJCF `<option>` (gravity, flags) and `<asset>` meshes, and the top-level elements that
casmech does not translate."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from casmech.importers.mjcf_defaults import Compiler, Defaults
from casmech.importers.mjcf_read import Reader

TRANSLATED = {"compiler", "option", "default", "asset", "worldbody", "equality", "actuator",
              "keyframe", "contact"}
QUIET = {"size", "visual", "statistic", "custom"}  # settings of MuJoCo's solver and viewer
GRAVITY = (0.0, 0.0, -9.81)


def unknown_sections(reader: Reader) -> None:
    for element in reader.root.children:
        if element.tag in TRANSLATED or element.tag in QUIET:
            continue
        if element.tag == "sensor" and element.children:
            reader.warn(element, "sensor", f"<sensor> with {len(element.children)} sensors not "
                        "translated (casmech's results hold positions, velocities and "
                        "reactions)")
        elif element.tag in ("tendon", "extension", "deformable"):
            for child in element.children:
                reader.warn(child, element.tag, f"<{element.tag}><{child.tag}> not translated")
        else:
            reader.warn(element, "mujoco", f"<{element.tag}> not translated")


def option(reader: Reader) -> tuple[list[float], bool, list[str]]:
    """(gravity, whether contacts are on, notes) of the `<option>` elements."""
    gravity, contact, notes = np.array(GRAVITY), True, []
    for element in reader.root.findall("option"):
        value = reader.numbers(element, element.attrib, "gravity", "option", (3,))
        if value is not None:
            gravity = value
        for key in ("density", "viscosity"):
            if float(element.attrib.get(key, "0") or 0) != 0:
                reader.warn(element, f"option.{key}", f"fluid {key} not translated (no drag "
                            "or buoyancy forces)")
        if "timestep" in element.attrib:
            notes.append(f"MuJoCo time step {element.attrib['timestep']} s (casmech's "
                         "integrators choose their own steps)")
        for flag in element.findall("flag"):
            if flag.attrib.get("gravity") == "disable":
                gravity = np.zeros(3)
            if flag.attrib.get("contact") == "disable":
                contact = False
            for key in ("equality", "actuation", "passive", "constraint"):
                if flag.attrib.get(key) == "disable":
                    reader.warn(flag, f"option.flag.{key}", f"flag {key}=\"disable\" not "
                                "translated: the model keeps them")
    return [float(g) for g in gravity], contact, notes


def meshes(reader: Reader, defaults: Defaults, compiler: Compiler, source: Path) -> dict:
    """Mesh asset name -> (file or None, scale per axis, the folder its file is relative to)."""
    found = {}
    base = source.parent / compiler.meshdir
    for block in reader.root.findall("asset"):
        for element in block.findall("mesh"):
            attrib = defaults.attributes(element, None, "asset.mesh")
            file = attrib.get("file")
            name = attrib.get("name") or (Path(file).stem if file else None)
            if name is None:
                raise reader.error(element, "asset.mesh", "a <mesh> has neither name nor file",
                                   'name="..." or file="..."', code="E100")
            scale = reader.numbers(element, attrib, "scale", "asset.mesh", (3,), (1, 1, 1))
            for key in ("refpos", "refquat"):
                if key in attrib:
                    reader.warn(element, f"asset.mesh.{key}", f"{key} not translated")
            found[name] = (file, scale, base)
    return found


def excluded(reader: Reader) -> tuple[set, set]:
    """Body pairs of `<contact><exclude>` (both orders) and, for `<pair>`, warnings."""
    pairs = set()
    for block in reader.root.findall("contact"):
        for element in block.children:
            if element.tag == "exclude":
                one, two = element.attrib.get("body1"), element.attrib.get("body2")
                pairs |= {(one, two), (two, one)}
            else:
                reader.warn(element, "contact", f"<contact><{element.tag}> not translated")
    return pairs, set()
