"""modelDescription.xml of an FMI 2.0 FMU for Model Exchange and Co-Simulation.

Variables in value-reference order (the C's, casmech_fmu.h): independent parameters (fixed or
tunable), states, their derivatives, inputs, outputs, calculated parameters, structural
parameters; ModelVariables lists them in that order, so a variable's index in ModelStructure
is its value reference plus one.
"""

from __future__ import annotations

import hashlib
import uuid
import xml.etree.ElementTree as ET
from collections.abc import Sequence

from casmech.core.columns import quantity
from casmech.core.records import record
from casmech.core.version import VERSION
from casmech.elements.coordinate_kinds import REGISTRY as COORDINATE_KINDS

# results-contract units (casmech.core.columns) -> FMI unit names and SI base exponents
UNITS = {
    "m": ("m", {"m": 1}), "m/s": ("m/s", {"m": 1, "s": -1}),
    "rad": ("rad", {"rad": 1}), "rad/s": ("rad/s", {"rad": 1, "s": -1}),
    "m/s²": ("m/s2", {"m": 1, "s": -2}), "rad/s²": ("rad/s2", {"rad": 1, "s": -2}),
    "N": ("N", {"kg": 1, "m": 1, "s": -2}), "N m": ("N.m", {"kg": 1, "m": 2, "s": -2}),
    "J": ("J", {"kg": 1, "m": 2, "s": -2}),
}
PARAMETER_WORDS = {
    "tunable": "tunable: may be set at events (Model Exchange) and between steps "
               "(Co-Simulation)",
    "fixed": "fixed: sets the initial state, so it may be set until initialization ends",
    "calculated": "calculated from the other parameters as the model defines it",
    "structural": "structural: it sets the model's structure (a count), fixed at its value "
                  "when the FMU was exported",
}
LOG_CATEGORIES = ("logStatusError", "logStatusWarning")


@record
class Variable:
    name: str
    causality: str
    variability: str
    initial: str | None
    start: float | None
    description: str = ""
    unit: str | None = None  # a key of UNITS
    derivative: int | None = None  # index (1-based) of the state this is the derivative of


def state_unit(name: str) -> str | None:
    coordinate = name.rsplit(".", 1)[-1]
    rate = coordinate.endswith("_dot")
    base = coordinate.removesuffix("_dot")
    if base in COORDINATE_KINDS:
        return COORDINATE_KINDS[base].quantity.units[1 if rate else 0]
    if base.startswith("angle"):
        return "rad/s" if rate else "rad"
    if base in ("x", "y", "z"):
        return "m/s" if rate else "m"
    if base.removesuffix("_j") in ("wx", "wy", "wz"):  # a spherical joint's: in body_j's frame
        return "rad/s"
    if base in ("vx", "vy", "vz"):
        return "m/s"
    return None


def column_unit(name: str) -> str | None:
    unit = quantity(name)[1]
    return unit if unit in UNITS else None


def _real(value: float) -> str:
    return repr(float(value))


def _element(variable: Variable, vr: int) -> ET.Element:
    attributes = {"name": variable.name, "valueReference": str(vr)}
    if variable.description:
        attributes["description"] = variable.description
    attributes |= {"causality": variable.causality, "variability": variable.variability}
    if variable.initial is not None:
        attributes["initial"] = variable.initial
    node = ET.Element("ScalarVariable", attributes)
    real = {}
    if variable.unit is not None:
        real["unit"] = UNITS[variable.unit][0]
    if variable.derivative is not None:
        real["derivative"] = str(variable.derivative)
    if variable.start is not None:
        real["start"] = _real(variable.start)
    ET.SubElement(node, "Real", real)
    return node


def _units(root: ET.Element, variables: Sequence[Variable]) -> None:
    used = sorted({v.unit for v in variables if v.unit is not None},
                  key=lambda u: UNITS[u][0])
    if not used:
        return
    units = ET.SubElement(root, "UnitDefinitions")
    for unit in used:
        name, exponents = UNITS[unit]
        ET.SubElement(ET.SubElement(units, "Unit", {"name": name}), "BaseUnit",
                      {k: str(v) for k, v in exponents.items()})


def _structure(root: ET.Element, variables: Sequence[Variable]) -> None:
    structure = ET.SubElement(root, "ModelStructure")
    outputs = [k + 1 for k, v in enumerate(variables) if v.causality == "output"]
    derivatives = [k + 1 for k, v in enumerate(variables) if v.derivative is not None]
    states = {v.derivative for v in variables if v.derivative is not None}
    initial = sorted({*outputs, *derivatives, *states,
                      *(k + 1 for k, v in enumerate(variables)
                        if v.causality == "calculatedParameter")})
    for tag, indices in (("Outputs", outputs), ("Derivatives", derivatives),
                         ("InitialUnknowns", initial)):
        if indices:
            group = ET.SubElement(structure, tag)
            for index in indices:
                ET.SubElement(group, "Unknown", {"index": str(index)})


def _interfaces(root: ET.Element, identifier: str, sources: Sequence[str], loops: bool) -> None:
    common = {"modelIdentifier": identifier, "needsExecutionTool": "false",
              "canBeInstantiatedOnlyOncePerProcess": "false",
              "canNotUseMemoryManagementFunctions": "false", "canGetAndSetFMUstate": "true",
              "canSerializeFMUstate": "true", "providesDirectionalDerivative": "false"}
    exchange = ET.SubElement(root, "ModelExchange", {
        **common, "completedIntegratorStepNotNeeded": "false" if loops else "true"})
    simulation = ET.SubElement(root, "CoSimulation", {
        **common, "canHandleVariableCommunicationStepSize": "true",
        "canInterpolateInputs": "true", "maxOutputDerivativeOrder": "0",
        "canRunAsynchronuously": "false"})
    for interface in (exchange, simulation):
        files = ET.SubElement(interface, "SourceFiles")
        for name in sources:
            ET.SubElement(files, "File", {"name": name})


def model_description(name: str, description: str, identifier: str,
                      variables: Sequence[Variable], sources: Sequence[str], loops: bool,
                      experiment: dict[str, float]) -> tuple[str, str]:
    """(the XML text, its GUID: a digest of everything else in it)."""
    def document(guid: str) -> str:
        root = ET.Element("fmiModelDescription", {
            "fmiVersion": "2.0", "modelName": name, "guid": guid,
            "description": description, "generationTool": f"casmech {VERSION}",
            "variableNamingConvention": "flat",
            "numberOfEventIndicators": "0"})
        _interfaces(root, identifier, sources, loops)
        _units(root, variables)
        categories = ET.SubElement(root, "LogCategories")
        for category in LOG_CATEGORIES:
            ET.SubElement(categories, "Category", {"name": category})
        ET.SubElement(root, "DefaultExperiment", {k: _real(v) for k, v in experiment.items()})
        model = ET.SubElement(root, "ModelVariables")
        for vr, variable in enumerate(variables):
            model.append(_element(variable, vr))
        _structure(root, variables)
        ET.indent(root)
        return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(
            root, encoding="unicode") + "\n"

    digest = hashlib.sha256(document("").encode()).hexdigest()
    guid = "{" + str(uuid.UUID(hex=digest[:32])) + "}"
    return document(guid), guid
