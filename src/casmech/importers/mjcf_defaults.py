"""MJCF `<default>` classes and `<compiler>` settings.

Default classes nest: `<default class="a">` inside `<default class="b">` starts from b's
attributes for every element type; the outermost `<default>` is the class `main`. An element
takes the attributes of its class (its `class` attribute, else the `childclass` of the
nearest enclosing body or frame that has one, else `main`), then its own. Defaults are kept
per element tag (an actuator shortcut such as `<position>` takes the defaults written for
`<position>`). Angles of `euler`, `axisangle` and of hinge joints' `ref`, `springref` and
`range` are in the compiler's `angle` unit (MJCF's default: degrees); Euler angles follow
`eulerseq` (default `xyz`; lower case: axes that rotate with the frame, upper case: fixed).
"""

from __future__ import annotations

import math

from casmech.core.records import record
from casmech.importers.mjcf_read import Element, Reader

MAIN = "main"


@record
class Compiler:
    degrees: bool = True  # compiler angle="degree" (MJCF's default)
    eulerseq: str = "xyz"
    inertiafromgeom: str = "auto"  # auto | true | false
    meshdir: str = ""
    boundmass: float = 0.0
    boundinertia: float = 0.0
    balanceinertia: bool = False
    autolimits: bool = True
    settotalmass: float = -1.0  # > 0: every mass and inertia scaled to this total

    def angle(self, value: float) -> float:
        return math.radians(value) if self.degrees else value


def compiler(reader: Reader) -> Compiler:
    """The settings of every `<compiler>` element (later ones override earlier ones)."""
    values: dict[str, str] = {}
    where: dict[str, Element] = {}
    for element in reader.root.findall("compiler"):
        values.update(element.attrib)
        where.update({key: element for key in element.attrib})
    if values.get("coordinate", "local") != "local":
        raise reader.error(where["coordinate"], "compiler.coordinate", "compiler "
                           "coordinate=\"global\" is not supported (MuJoCo 2.3.3 removed it)",
                           'coordinate="local"', code="E103")
    angle = reader.choice(where.get("angle", reader.root), values, "angle", "compiler",
                          ("degree", "radian"), "degree")
    sequence = values.get("eulerseq", "xyz")
    if len(sequence) != 3 or any(c not in "xyzXYZ" for c in sequence):
        raise reader.error(where["eulerseq"], "compiler.eulerseq", "eulerseq must be three of "
                           "x, y, z, X, Y, Z", "e.g. xyz or ZYX", got=repr(sequence))
    flag = {"true": True, "false": False}
    element = where.get("inertiafromgeom", reader.root)
    numbers = {key: reader.number(where.get(key, reader.root), values, key, "compiler", 0.0)
               for key in ("boundmass", "boundinertia")}
    numbers["settotalmass"] = reader.number(where.get("settotalmass", reader.root), values,
                                            "settotalmass", "compiler", -1.0)
    return Compiler(
        degrees=angle == "degree", eulerseq=sequence,
        inertiafromgeom=reader.choice(element, values, "inertiafromgeom", "compiler",
                                      ("auto", "true", "false"), "auto"),
        meshdir=values.get("meshdir", values.get("assetdir", "")), **numbers,
        balanceinertia=flag.get(values.get("balanceinertia", "false"), False),
        autolimits=flag.get(values.get("autolimits", "true"), True))


class Defaults:
    """Default classes: name -> {tag: attributes} (inherited attributes included)."""

    def __init__(self, reader: Reader):
        self.reader = reader
        self.classes: dict[str, dict[str, dict[str, str]]] = {MAIN: {}}
        self.where: dict[str, Element] = {}
        for element in reader.root.findall("default"):
            self._read(element, MAIN, top=True)

    def _read(self, element: Element, parent: str, top: bool = False) -> None:
        name = element.attrib.get("class", MAIN if top else None)
        if name is None:
            raise self.reader.error(element, "default", "a nested <default> has no 'class'",
                                    'class="name"', code="E100")
        if name in self.where and not (top and name == MAIN):
            raise self.reader.error(element, f"default[{name}]", f"a second default class "
                                    f"named '{name}'", "a class name used once", code="E301",
                                    hint=f"the first is at line {self.where[name].line}")
        self.where[name] = element
        tags = {tag: dict(values) for tag, values in self.classes[parent].items()} \
            if name != parent else self.classes[name]
        for child in element.children:
            if child.tag != "default":
                tags.setdefault(child.tag, {}).update(child.attrib)
        self.classes[name] = tags
        for child in element.findall("default"):
            self._read(child, name)

    def attributes(self, element: Element, childclass: str | None, path: str) -> dict[str, str]:
        """The element's attributes after its class's defaults."""
        name = element.attrib.get("class", childclass or MAIN)
        if name not in self.classes:
            from casmech.errors import did_you_mean

            raise self.reader.error(element, f"{path}.class", f"unknown default class "
                                    f"'{name}'", "the class of a <default>", code="E300",
                                    got=name, hint=did_you_mean(name, self.classes) or None)
        return {**self.classes[name].get(element.tag, {}), **element.attrib}

    def childclass(self, element: Element, inherited: str | None, path: str) -> str | None:
        name = element.attrib.get("childclass", inherited)
        if name is not None and name not in self.classes:
            raise self.reader.error(element, f"{path}.childclass", f"unknown default class "
                                    f"'{name}'", "the class of a <default>", code="E300",
                                    got=name)
        return name
