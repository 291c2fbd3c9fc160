"""The system functions of a model with a `theta` input: the parametric bundle.

theta holds file parameters (any of them: masses, inertias, gravity, forces, drivers and
geometry: lengths, joint points, axes, initial poses, the parameters of a composed model and
of its instances, `<instance>.<name>`) and initial-velocity offsets `<body>.vx` .. `<body>.wz`
(added to that body's initial velocity in the file, before it is projected onto the
constraints).

The model is loaded again with those parameters symbolic (schema.load_model_text's
`symbolic`, with the `--set` values it was loaded with), so the schema and the lowering carry
every number computed from them as a traced number (casmech.core.traced); the velocity
offsets are added to the lowered bodies as traced numbers too. model.parametric splits that
IR into its structure and its model data d, with d(theta) as an expression graph; every
function here is equations.functions' bundle over d called with d = d(theta). So the functions
are exact at every theta, and every derivative with respect to theta comes from CasADi. What is
fixed is the structure at the model's values: which numbers are zero without depending on
theta, counts, and the branches the lowering took (an axis's perpendicular pair, the form of a
quaternion); a parameter that sets a count is refused.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import replace

import casadi as ca
import numpy as np

from casmech.core import euler, traced
from casmech.core.records import record
from casmech.core.values import constant
from casmech.equations import initial_rows, readings
from casmech.equations.assemble import Coordinates
from casmech.equations.functions import SystemFunctions, build_functions
from casmech.errors import ModelError, UsageError
from casmech.model import parametric
from casmech.model.ir import ModelIR
from casmech.model.lower import lower
from casmech.schema import load_model_text
from casmech.schema.loader import load_document
from casmech.schema.resolved import ResolvedModel

VELOCITY_KEYS = {"vx": ("r_dot0", 0), "vy": ("r_dot0", 1), "vz": ("r_dot0", 2),
                 "wx": ("omega0", 0), "wy": ("omega0", 1), "wz": ("omega0", 2)}
# the functions of a ParametricSystem that come from equations.functions' bundle
BUNDLE = ("phi", "phi_q", "phi_scaled", "nu", "gamma", "mass_matrix", "generalized_forces",
          "energy", "reactions", "element_outputs")
SAME = 8  # ulps within which the model loaded again must give each parameter's value


@record
class ParametricSystem:
    """Named casadi.Functions with a trailing `theta` input, and the nominal bundle."""

    functions: dict[str, ca.Function]
    nominal: SystemFunctions  # casmech.compile of the same model (theta = values)
    names: tuple[str, ...]  # what theta holds, in order
    values: np.ndarray  # theta in the file (initial-velocity offsets: 0)
    data: ca.Function  # theta -> d, the model data (model.parametric) as a function
    split: parametric.Split  # the lowering with theta traced, split into structure and d
    # equations.functions' bundle over d (its functions' trailing input), which `functions`
    # call with d = d(theta): what a formulation's residual is built over
    over_data: SystemFunctions | None = None

    def __getitem__(self, name: str) -> ca.Function:
        return self.functions[name]

    @property
    def n_coordinates(self) -> int:
        return self.nominal.n_coordinates


def classify(model: ResolvedModel, names: Iterable[str]) -> tuple[list[str], list[str]]:
    """(file parameters, initial-velocity names); a usage error for anything else."""
    bodies = {b.name for b in model.bodies}
    parameters, velocities = [], []
    for name in names:
        body, _, key = name.rpartition(".")
        if name in model.parameters:
            parameters.append(name)
        elif body in bodies and key in VELOCITY_KEYS:
            velocities.append(name)
        else:
            known = ", ".join(model.parameters) or "none"
            raise UsageError(f"'{name}' is neither a parameter of the model nor an initial "
                             f"velocity <body>.vx..vz/.wx..wz; parameters: {known}")
    return parameters, velocities


def located(model: ResolvedModel, name: str, message: str) -> UsageError:
    """'FILE:LINE:COL: parameter 'NAME' MESSAGE', at the parameter's key when the model's own
    file writes it (an instance's parameter: the file alone)."""
    document = load_document(model.text, model.file)
    written = document.data.get("parameters") or {}
    where = document.locate_key(("parameters", name)) if name in written else model.file
    return UsageError(f"{where}: parameter '{name}' {message}")


def traced_model(model: ResolvedModel, parameters: Sequence[str]) -> ResolvedModel:
    """The model loaded again with `parameters` symbolic; a located usage error if that is
    refused (a parameter that sets a count) or does not give the model's parameter values
    (a model that was not loaded from its text and overrides)."""
    if not parameters:
        return model
    try:
        again = load_model_text(model.text, model.file, model.overrides, symbolic=parameters)
    except ModelError as error:
        raise located(model, parameters[0], "cannot be a variable: "
                      f"{error.diagnostics[0].format()}") from None
    for name, value in model.parameters.items():
        got = traced.value(again.parameters.get(name, np.nan))
        if not abs(got - value) <= SAME * np.spacing(abs(value)):
            raise located(model, parameters[0], f"cannot be a variable of this model: loaded "
                          f"again from its text and overrides ({dict(model.overrides)}), it "
                          f"gives {name} = {got!r}, not {value!r}")
    return again


def _with_offsets(ir: ModelIR, velocities: Sequence[str], symbols) -> ModelIR:
    """The bodies' initial velocities plus the offsets `<body>.vx`.. (traced numbers)."""
    bodies = {b.name: b for b in ir.bodies}
    for name in velocities:
        body, _, key = name.rpartition(".")
        field, index = VELOCITY_KEYS[key]
        vector = list(getattr(bodies[body], field))
        vector[index] = vector[index] + traced.seed(0.0, symbols[name])
        bodies[body] = replace(bodies[body], **{field: traced.array(vector)})
    return replace(ir, bodies=tuple(bodies[b.name] for b in ir.bodies))


def _function(name, inputs: dict, outputs: dict) -> ca.Function:
    return ca.Function(name, list(inputs.values()), list(outputs.values()),
                       list(inputs), list(outputs))


def _start(ir: ModelIR, d) -> dict[str, ca.Function]:
    """file_velocities(q, d) and initial_guess(d) of the split IR: the file's velocities (with
    the offsets) and pose, where assembly starts."""
    x = Coordinates.create(ir.n_bodies)
    q, bodies = x.q, ir.bodies
    velocities = [constant(b.r_dot0) for b in bodies]
    velocities += [0.5 * euler.e_matrix(x.p(k)).T @ constant(b.omega0)
                   for k, b in enumerate(bodies)]
    pose = [constant(b.r0) for b in bodies] + [constant(b.p0) for b in bodies]
    empty = ca.SX(0, 1)
    return {"file_velocities": _function("file_velocities", {"q": q, "d": d},
                                         {"q_dot": ca.vertcat(*velocities) if bodies
                                          else empty}),
            "initial_guess": _function("initial_guess", {"d": d},
                                       {"q": ca.vertcat(*pose) if bodies else empty}),
            **_held(ir, d)}


def _held(ir: ModelIR, d) -> dict[str, ca.Function]:
    """held_positions(q, d): the rows of the joints' `initial:` values assembly holds, and
    held_rates(q, d): the rates' rows (their Jacobian in q_dot) and targets
    (equations/initial_rows.py); none without such values."""
    if not any(joint.initial for joint in ir.joints):
        return {}
    x = Coordinates.create(ir.n_bodies)
    positions, rates = initial_rows.positions(ir, x), initial_rows.rates(ir, x)
    jacobian = x.ground_fixed(ca.jacobian(rates.values, x.q_dot))
    return {"held_positions": _function("held_positions", {"q": x.q, "d": d},
                                        {"rows": x.ground_fixed(positions.values)}),
            "held_rates": _function("held_rates", {"q": x.q, "d": d},
                                    {"jacobian": jacobian, "targets": rates.targets})}


def _bound(function: ca.Function, theta, d) -> ca.Function:
    """A function whose trailing input is the model data, with theta in its place and
    d = d(theta) inside."""
    inputs = [ca.SX.sym(function.name_in(k), function.sparsity_in(k))
              for k in range(function.n_in() - 1)]
    return ca.Function(function.name(), [*inputs, theta], function.call([*inputs, d]),
                       [*function.name_in()[:-1], "theta"], function.name_out())


def parametric_system(model: ResolvedModel, names: Iterable[str] = ()) -> ParametricSystem:
    """The model's system functions with `names` (parameters, `<body>.vx`..) as `theta`
    (module docstring)."""
    names = tuple(dict.fromkeys(names))
    parameters, velocities = classify(model, names)
    again = traced_model(model, parameters)
    symbols = {**again.symbols, **{name: ca.SX.sym(name) for name in velocities}}
    split = parametric.split(_with_offsets(lower(again), velocities, symbols))
    theta = ca.vertcat(*(symbols[n] for n in names)) if names else ca.SX(0, 1)
    bundle = build_functions(split.ir, split.symbols)
    over_d = {name: bundle[name] for name in BUNDLE} | _start(split.ir, split.symbols)
    over_d["readings"] = readings.columns_function(split.ir, split.symbols)
    functions = {name: _bound(f, theta, split.expressions) for name, f in over_d.items()}
    values = np.array([model.parameters.get(n, 0.0) for n in names], float)
    return ParametricSystem(functions, build_functions(lower(model)), names, values,
                            split.data_function(theta), split, bundle)
