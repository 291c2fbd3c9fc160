"""What an FMU of a model exposes, and the model lowered over its parameters and inputs.

Parameters: the model file's own parameters (`parameters:`). One whose value is a number, or
an expression of no other parameter, is independent: it becomes a symbol theta of the traced
lowering (optimal.system.traced_model), so that every number computed from it (masses,
lengths, joint points, initial poses) is an expression of theta. Its FMI variability:

- `fixed` when the file's initial pose or velocities depend on it (settable until the end of
  initialization, when the start state is computed from it);
- `tunable` otherwise (masses, inertias, forces, gravity, driver constants: settable between
  steps and at events too);
- not settable (an FMI constant) when the structure depends on it (a repeat count: the traced
  load refuses it).

A parameter defined from others is a calculated parameter: its value follows theta, as
`--set` of the independent ones recomputes it.

Inputs: every effort motor (`<joint>.torque` or `<joint>.force`) and every control of the
model's `ocp:` block (a motor of that kind added to its joint, zero law) unless `inputs`
names a subset. An input replaces the motor's law: its torque or force is the input's value.
The inputs are appended to the model data, so every function of the lowered model takes
[d; u] as its data.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import casadi as ca

from casmech.core import traced
from casmech.core.expressions import ExpressionError, parse
from casmech.core.records import record
from casmech.elements.coordinate_kinds import BY_TYPE, View
from casmech.elements.coordinate_kinds import REGISTRY as COORDINATE_KINDS
from casmech.equations.motors import INPUTS
from casmech.errors import UsageError
from casmech.model import parametric
from casmech.model.ir import ModelIR
from casmech.model.lower import lower
from casmech.optimal.system import traced_model
from casmech.schema.loader import load_document
from casmech.schema.resolved import ResolvedModel, ScalarFunction

KINDS = ("tunable", "fixed", "calculated", "structural")
# effort motor mode -> the variables its law reads (t, its coordinate kind's value and rate)
CONTROL_VARIABLES = View(lambda: {kind.motor[2]: ("t", *kind.attributes)
                                  for kind in COORDINATE_KINDS.values()})


@record
class Parameter:
    name: str
    value: float
    kind: str  # one of KINDS


@record
class Input:
    name: str  # "<joint>.torque" | "<joint>.force"
    joint: str
    kind: str  # torque | force
    control: bool  # an `ocp:` control (else the joint's effort motor)


@record
class Exported:
    """The model as the FMU computes it: the lowered IR with theta traced, split into its
    structure and model data d (d(theta): split.expressions), effort motors' laws replaced
    by the inputs u, every function's data [d; u]."""

    model: ResolvedModel
    parameters: tuple[Parameter, ...]
    theta: ca.SX  # the independent parameters' symbols, in `parameters` order
    calculated: ca.SX  # the calculated parameters as expressions of theta
    split: parametric.Split
    ir: ModelIR  # split.ir with the inputs in place of the motor laws
    inputs: tuple[Input, ...]
    u: ca.SX

    @property
    def data(self) -> ca.SX:
        """[d; u]: the trailing input of the lowered model's functions."""
        return ca.vertcat(self.split.symbols, self.u)

    @property
    def n_data(self) -> int:
        return self.split.symbols.numel()

    def named(self, kind: str) -> list[Parameter]:
        return [p for p in self.parameters if p.kind == kind]


def definitions(model: ResolvedModel) -> dict[str, str]:
    """Each parameter of the model file as written (or as `--set` gives it), as text."""
    written = load_document(model.text, model.file).data.get("parameters") or {}
    if not isinstance(written, dict):
        return {}
    texts = {name: str(value) for name, value in written.items() if name in model.parameters}
    return texts | {k: v for k, v in model.overrides.items() if k in texts}


def independent(model: ResolvedModel) -> list[str]:
    """The file's parameters whose definition names no other parameter."""
    texts = definitions(model)
    names = []
    for name, text in texts.items():
        try:
            symbols = parse(text).symbols
        except ExpressionError:
            continue
        if not symbols & model.parameters.keys():
            names.append(name)
    return names


def traceable(model: ResolvedModel, names: Sequence[str]) -> tuple[list[str], ResolvedModel]:
    """(the names the traced load accepts, the model loaded with them symbolic): a
    count-setting parameter is refused alone."""
    try:
        return list(names), traced_model(model, list(names))
    except UsageError:
        accepted = []
        for name in names:
            try:
                traced_model(model, [name])
                accepted.append(name)
            except UsageError:
                continue
        return accepted, traced_model(model, accepted)


def with_controls(model: ResolvedModel) -> ResolvedModel:
    """The model with an effort motor (zero law) on the joint of each `ocp:` control that
    has none of that kind."""
    if model.ocp is None:
        return model
    wanted: dict[str, set[str]] = {}
    for control in model.ocp.controls:
        wanted.setdefault(control.joint, set()).add(control.type)
    zero = parse("0")
    joints = []
    for joint in model.joints:
        motor = dict(joint.motor)
        for kind in sorted(wanted.get(joint.name, ())):
            motor.setdefault(kind, ScalarFunction("0", zero, {}, CONTROL_VARIABLES[kind]))
        joints.append(replace(joint, motor=motor) if motor != dict(joint.motor) else joint)
    return replace(model, joints=tuple(joints))


def available_inputs(model: ResolvedModel) -> list[Input]:
    """Every effort motor's and `ocp:` control's input, in joint order."""
    controls = {(c.joint, c.type) for c in (model.ocp.controls if model.ocp else ())}
    return [Input(f"{joint.name}.{kind}", joint.name, kind, (joint.name, kind) in controls)
            for joint in with_controls(model).joints for kind in joint.motor
            if kind in CONTROL_VARIABLES]


def chosen_inputs(model: ResolvedModel, names: Sequence[str] | None) -> list[Input]:
    """The inputs `names` selects (None: all; "none" alone: no input)."""
    every = available_inputs(model)
    if names is None:
        return every
    if list(names) == ["none"]:
        return []
    known = {i.name: i for i in every}
    unknown = [n for n in names if n not in known]
    if unknown:
        offered = ", ".join(known) or "none (the model has no effort motor and no ocp: control)"
        raise UsageError(f"--inputs {unknown[0]}: not an effort motor or ocp: control of the "
                         f"model; inputs: {offered}")
    return [known[n] for n in dict.fromkeys(names)]


def _with_inputs(ir: ModelIR, inputs: Sequence[Input], u: ca.SX) -> ModelIR:
    """The IR with the chosen motors' laws replaced by the inputs."""
    index = {(i.joint, i.kind): k for k, i in enumerate(inputs)}
    motors = []
    for motor in ir.motors:
        kind = BY_TYPE[motor.type][0].motor[2]  # its effort mode
        k = index.get((motor.name, kind))
        motors.append(motor if k is None else INPUTS[motor.type][1](motor, u[k:k + 1]))
    return replace(ir, motors=tuple(motors))


def _initial(ir: ModelIR) -> ca.SX:
    """The file's initial pose and velocities of every body (as the IR holds them)."""
    parts = [ca.SX(v) for b in ir.bodies for v in (b.r0, b.p0, b.r_dot0, b.omega0)]
    return ca.vertcat(ca.SX(0, 1), *(ca.vec(p) for p in parts))


def exported(model: ResolvedModel, input_names: Sequence[str] | None = None) -> Exported:
    """The model's FMU view (module docstring)."""
    inputs = chosen_inputs(model, input_names)
    free = independent(model)
    names, again = traceable(model, free)
    again = with_controls(again)
    split = parametric.split(lower(again))
    theta = ca.vertcat(ca.SX(0, 1), *(again.symbols[n] for n in names))
    d_of_theta = ca.Function("d", [split.symbols], [_initial(split.ir)])(split.expressions)
    kinds = {}
    for k, name in enumerate(names):
        kinds[name] = "fixed" if ca.depends_on(d_of_theta, theta[k]) else "tunable"
    structural = [n for n in free if n not in names]
    derived = [n for n in model.parameters if n not in free and n in definitions(model)]
    calculated = ca.vertcat(ca.SX(0, 1), *(
        traced.expression(again.parameters[n]) for n in derived))
    order = [*names, *derived, *structural]
    parameters = tuple(Parameter(n, float(model.parameters[n]), kinds.get(
        n, "calculated" if n in derived else "structural")) for n in order)
    u = ca.SX.sym("u", len(inputs))
    return Exported(model, parameters, theta, calculated, split,
                    _with_inputs(split.ir, inputs, u), tuple(inputs), u)
