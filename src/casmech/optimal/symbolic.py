"""Re-lower a model with chosen parameters left as CasADi symbols.

The compiler evaluates every parameter to a number while lowering. Here the fields that depend on
the chosen parameters are evaluated again from the file's expressions with the CasADi backend:
masses, inertias, gravity, force-law coefficients, functions of time (drivers, actuators, applied
forces) and initial velocities. A parameter that moves the geometry written in the file (positions,
orientations, joint points and axes) is refused (system.py's method "data" takes those): which
fields move is found by lowering the model again at a perturbed value, so nothing here enumerates
the geometry keys of the format.

Initial conditions are "parameters" too: `<body>.vx .. .vz`, `<body>.wx .. .wz` name an offset
added to that body's initial velocity in the file (before it is projected onto the constraints).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from casmech.core.expressions import parse
from casmech.errors import ModelError, UsageError
from casmech.model.ir import ModelIR
from casmech.model.lower import lower
from casmech.optimal.lowering import Lowering
from casmech.schema.components import uses_composition
from casmech.schema.loader import load_document
from casmech.schema.resolved import ResolvedModel
from casmech.schema.spec_errors import validate

VELOCITY_KEYS = {"vx": ("r_dot0", 0), "vy": ("r_dot0", 1), "vz": ("r_dot0", 2),
                 "wx": ("omega0", 0), "wy": ("omega0", 1), "wz": ("omega0", 2)}
GEOMETRY_FIELDS = {  # IR part -> fields that must not move with a symbolic parameter
    "bodies": ("r0", "p0"),
    "primitives": ("vectors", "offset"),
    "joints": ("point_i",),
    "forces": ("points", "axes"),
}


@dataclass(frozen=True)
class SymbolicModel:
    """A ModelIR whose parameter-dependent fields are CasADi expressions of `theta`."""

    ir: ModelIR  # symbolic fields (SX) where they depend on theta
    numeric: ModelIR  # the same model with every field a number (theta = values)
    names: tuple[str, ...]
    values: np.ndarray
    theta: ca.SX


def _scalar(value, env: Mapping, dependent: set[str]):
    """The CasADi value of a file scalar when it depends on a symbolic name, else None."""
    if value is None or not isinstance(value, str):
        return None
    expr = parse(value)
    return expr.evaluate(env, "casadi") if expr.symbols & dependent else None


def _environment(spec, model: ResolvedModel, symbols: Mapping[str, ca.SX]):
    """Every parameter's value (symbolic where it depends on a chosen one) and the dependents."""
    env, dependent = {}, set()
    for name, value in spec.parameters.items():
        if name in symbols:
            env[name], dependent = symbols[name], dependent | {name}
            continue
        symbolic = _scalar(value, env, dependent)
        if symbolic is None:
            env[name] = model.parameters[name]
        else:
            env[name], dependent = symbolic, dependent | {name}
    return env, dependent


def _inertia(given, env, dependent):
    entries = [x for row in given for x in row] if isinstance(given[0], tuple) else list(given)
    values = [_scalar(x, env, dependent) for x in entries]
    if all(v is None for v in values):
        return None
    value = [v if v is not None else parse(str(x)).evaluate(env, "casadi")
             for v, x in zip(values, entries, strict=True)]
    if len(value) == 9:
        return ca.reshape(ca.vertcat(*value), 3, 3).T
    if len(value) == 3:
        return ca.diag(ca.vertcat(*value))
    xx, yy, zz, xy, xz, yz = value
    return ca.blockcat([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def _vector(given, numeric: np.ndarray, env, dependent, offset=None):
    values = [_scalar(x, env, dependent) for x in (given or (0, 0, 0))]
    vector = ca.vertcat(*[v if v is not None else float(n) for v, n in zip(values, numeric,
                                                                         strict=True)])
    if offset is not None:
        vector = vector + offset
    depends = any(v is not None for v in values) or offset is not None
    return vector if depends else numeric


def _bodies(ir: ModelIR, spec, env, dependent, offsets):
    bodies = []
    for body, given in zip(ir.bodies, spec.bodies, strict=True):
        mass = _scalar(given.mass, env, dependent)
        inertia = _inertia(given.inertia, env, dependent)
        fields = {"mass": mass, "inertia": inertia,
                  "r_dot0": _vector(given.velocity, body.r_dot0, env, dependent,
                                    offsets.get((body.name, "r_dot0"))),
                  "omega0": _vector(given.angular_velocity, body.omega0, env, dependent,
                                    offsets.get((body.name, "omega0")))}
        bodies.append(replace(body, **{k: v for k, v in fields.items() if v is not None}))
    return tuple(bodies)


def _bind(function, env):
    """A ScalarFunction with the (possibly symbolic) parameter values bound."""
    if function is None:
        return None
    return replace(function, constants={**function.constants,
                                        **{k: env[k] for k in function.constants if k in env}})


def _forces(ir: ModelIR, spec, env, dependent):
    forces = []
    for force, given in zip(ir.forces, spec.forces, strict=True):
        params = dict(force.params)
        for key in params:
            value = _scalar(getattr(given, key, None), env, dependent)
            params[key] = params[key] if value is None else value
        value = tuple(_bind(f, env) for f in force.value) if force.value else force.value
        forces.append(replace(force, params=params, actuator=_bind(force.actuator, env),
                              value=value))
    return tuple(forces)


def offsets(names: Iterable[str], symbols: Mapping[str, ca.SX]):
    """Initial-velocity offsets: (body, field) -> 3-vector of symbols and zeros."""
    offsets: dict = {}
    for name in names:
        body, _, key = name.rpartition(".")
        field, index = VELOCITY_KEYS[key]
        vector = offsets.setdefault((body, field), ca.SX.zeros(3))
        vector[index] = symbols[name]
    return offsets


def _moved(a: ModelIR, b: ModelIR) -> list[str]:
    """Geometry fields that differ between two numeric lowerings (by name)."""
    moved = []
    for part, fields in GEOMETRY_FIELDS.items():
        for item_a, item_b in zip(getattr(a, part), getattr(b, part), strict=True):
            for field in fields:
                va, vb = getattr(item_a, field), getattr(item_b, field)
                pairs = [(va[k], vb[k]) for k in va] if isinstance(va, Mapping) else [(va, vb)]
                if any(not np.allclose(x, y, rtol=1e-12, atol=1e-14) for x, y in pairs):
                    moved.append(f"{part} '{getattr(item_a, 'name', None) or item_a.row.joint}'"
                                 f" {field}")
    return moved


def geometry_moved(model: ResolvedModel, names: Iterable[str]) -> str | None:
    """'parameter NAME moves the model's geometry (FIELD)' for the first of `names` (file
    parameters) that does, found by lowering the model again with it bumped; None if none
    does. A composed model counts as moved (its expressions are not re-read here)."""
    names = tuple(names)
    if _composed(model):
        return f"{model.file} is composed (components, instances or repeat)"
    ir, lowering = lower(model), Lowering(model)
    for name in names:
        value = model.parameters[name]
        try:
            moved = _moved(ir, lowering.ir(name, value + 1e-3 * (1.0 + abs(value))))
        except (ModelError, ValueError):  # another structure: the "data" method says so
            moved = ["its structure"]
        if moved:
            return f"parameter '{name}' moves the model's geometry ({moved[0]})"
    return None


def _composed(model: ResolvedModel) -> bool:
    return bool(model.files) or uses_composition(load_document(model.text, model.file).data)


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


def symbolic_model(model: ResolvedModel, names: Iterable[str]) -> SymbolicModel:
    """The model lowered with `names` (parameters and initial velocities) as symbols."""
    names = tuple(dict.fromkeys(names))
    parameters, velocities = classify(model, names)
    theta = ca.SX.sym("theta", len(names))
    symbols = {name: theta[k] for k, name in enumerate(names)}
    document = load_document(model.text, model.file)
    if model.files or uses_composition(document.data):
        raise UsageError(f"{model.file} is composed (components, instances or repeat): "
                         "method 'symbolic' re-reads a flat model's own expressions; a composed "
                         "model's parameters go through its model data (method 'data' or "
                         "'auto')")
    spec, _ = validate(document)
    env, dependent = _environment(spec, model, {n: symbols[n] for n in parameters})
    numeric = lower(model)
    moved = geometry_moved(model, parameters)
    if moved:
        raise UsageError(f"{moved}; method 'symbolic' takes parameters of masses, inertias, "
                         "gravity, forces, drivers and initial velocities (sensitivities to "
                         "geometry: method 'data' or 'auto')")
    gravity = _vector(spec.gravity, numeric.gravity, env, dependent)
    ir = replace(numeric, bodies=_bodies(numeric, spec, env, dependent,
                                         offsets(velocities, symbols)),
                 forces=_forces(numeric, spec, env, dependent), gravity=gravity,
                 primitives=tuple(replace(p, f=_bind(p.f, env)) for p in numeric.primitives),
                 motors=tuple(replace(m, actuator=_bind(m.actuator, env))  # effort motors
                              for m in numeric.motors))
    values = np.array([model.parameters.get(n, 0.0) for n in names], float)
    return SymbolicModel(ir, numeric, names, values, theta)

