"""The system functions of a model with a `theta` input: the parametric bundle.

Two ways to make theta an input (`method`):

- "symbolic": the same builders as `casmech.compile` (equations/assemble.py, equations/eom.py) run
  on the symbolic IR of `symbolic.py` (the file's expressions re-evaluated with CasADi), and
  every function gets one more input, `theta`. Inertias and gravity enter the compiler's builders
  as numeric matrices; both enter the equations linearly, so a symbolic inertia or gravity is
  applied exactly as a linear combination of the builders evaluated at unit entries (the
  builders stay the single source of the formulas). Exact at every theta; geometry refused.
- "data": equations.functions over model.parametric's split IR (every number of the lowering
  an entry of the model data d), with d = d0 + D (theta - theta0) and D = dd/dtheta from
  `lowering.py` (central differences of the NumPy lowering). Any parameter that keeps the
  structure, geometry included; the functions are the model's at theta0 and their first
  derivatives there (what sensitivities need), not the model at another theta.

Both add `file_velocities(q, theta)` (the file's velocities, with the `<body>.vx`.. offsets)
and `initial_guess(theta)` (the file's pose: where assembly starts).

For evaluations away from theta0 (estimation), `data_inputs` builds the system over the moving
entries of d themselves, with d(theta) exact at every theta through model_data.ModelData.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.core.values import constant
from casmech.equations import eom
from casmech.equations.assemble import Coordinates, build_constraints
from casmech.equations.functions import SystemFunctions, build_functions
from casmech.errors import UsageError
from casmech.model.ir import ModelIR
from casmech.model.lower import lower
from casmech.optimal import lowering
from casmech.optimal.model_data import ModelData
from casmech.optimal.symbolic import (
    SymbolicModel,
    classify,
    geometry_moved,
    offsets,
    symbolic_model,
)
from casmech.schema.resolved import ResolvedModel

METHODS = ("auto", "symbolic", "data")
# the functions of a ParametricSystem that come from equations.functions' bundle
BUNDLE = ("phi", "phi_q", "phi_scaled", "nu", "gamma", "mass_matrix", "generalized_forces",
          "energy", "reactions")


@dataclass(frozen=True)
class ParametricSystem:
    """Named casadi.Functions with a `theta` input, and the nominal compiled bundle."""

    functions: dict[str, ca.Function]
    nominal: SystemFunctions  # casmech.compile of the same model (theta = values)
    names: tuple[str, ...]  # what theta holds, in order
    values: np.ndarray  # theta in the file (initial-velocity offsets: 0)
    method: str = "symbolic"  # how theta entered (module docstring)
    # "data": the estimated relative error of dd/dtheta per file parameter (lowering.py)
    lowering_error: dict[str, float] | None = None

    def __getitem__(self, name: str) -> ca.Function:
        return self.functions[name]

    @property
    def n_coordinates(self) -> int:
        return self.nominal.n_coordinates


def _is_symbolic(value) -> bool:
    return isinstance(value, (ca.SX, ca.MX))


def _unit(shape, index) -> np.ndarray:
    e = np.zeros(shape)
    e[index] = 1.0
    return e


def _variants(ir: ModelIR):
    """(numeric base IR, [(coefficient, IR with one unit entry)]) for symbolic inertias and
    gravity; the base holds zeros where the symbolic values go."""
    bodies = tuple(replace(b, inertia=np.zeros((3, 3))) if _is_symbolic(b.inertia) else b
                   for b in ir.bodies)
    symbolic_gravity = _is_symbolic(ir.gravity)
    base = replace(ir, bodies=bodies, gravity=np.zeros(3) if symbolic_gravity else ir.gravity)
    terms = []
    for k, body in enumerate(ir.bodies):
        if not _is_symbolic(body.inertia):
            continue
        for a, b in np.ndindex(3, 3):
            unit = replace(bodies[k], inertia=_unit((3, 3), (a, b)))
            terms.append((body.inertia[a, b],
                          replace(base, bodies=bodies[:k] + (unit,) + bodies[k + 1:])))
    if symbolic_gravity:
        terms += [(ir.gravity[i], replace(base, gravity=_unit(3, i))) for i in range(3)]
    return base, terms


def linear(builder: Callable[[ModelIR], tuple], ir: ModelIR) -> list:
    """builder(ir) for an IR with symbolic inertias/gravity (builder affine in each)."""
    base, terms = _variants(ir)
    total = list(builder(base))
    for coefficient, variant in terms:
        total = [s + coefficient * (v - b)
                 for s, v, b in zip(total, builder(variant), builder(base), strict=True)]
    return total


def _function(name, inputs: dict, outputs: dict) -> ca.Function:
    return ca.Function(name, list(inputs.values()), list(outputs.values()),
                       list(inputs), list(outputs))


def build_parametric(symbolic: SymbolicModel) -> dict[str, ca.Function]:
    ir, theta = symbolic.ir, symbolic.theta
    cs = build_constraints(ir)
    x = cs.x
    t, q, q_dot = x.t, x.q, x.q_dot
    lam = ca.SX.sym("lam", cs.phi.numel())
    fixed = x.ground_fixed
    mass, = linear(lambda i: (eom.mass_matrix(i, x),), ir)
    applied, spring = linear(lambda i: eom.applied_forces(i, x), ir)
    quadratic, = linear(lambda i: (eom.quadratic_velocity(i, x),), ir)
    kinetic, potential = linear(lambda i: eom.energy(i, x, spring), ir)
    force, torque = eom.reactions(ir, x, cs.phi_with_ground, lam)
    definitions = [
        ("phi", {"t": t, "q": q, "theta": theta}, {"phi": cs.phi}),
        ("phi_q", {"t": t, "q": q, "theta": theta}, {"phi_q": cs.phi_q}),
        ("phi_scaled", {"t": t, "q": q, "s": cs.scale, "theta": theta},
         {"phi": cs.phi_scaled, "phi_q": cs.phi_q_scaled}),
        ("nu", {"t": t, "q": q, "theta": theta}, {"nu": cs.nu}),
        ("gamma", {"t": t, "q": q, "q_dot": q_dot, "theta": theta}, {"gamma": cs.gamma}),
        ("mass_matrix", {"q": q, "theta": theta}, {"mass_matrix": mass}),
        ("generalized_forces", {"t": t, "q": q, "q_dot": q_dot, "theta": theta},
         {"generalized_forces": fixed(applied + quadratic)}),
        ("energy", {"t": t, "q": q, "q_dot": q_dot, "theta": theta},
         {"kinetic": fixed(kinetic), "potential": fixed(potential)}),
        ("reactions", {"t": t, "q": q, "q_dot": q_dot, "lam": lam, "theta": theta},
         {"force": fixed(force), "torque": fixed(torque)}),
    ]
    functions = {name: _function(name, *io) for name, *io in definitions}
    return functions | _start(ir, x, theta)


def _start(ir: ModelIR, x, theta) -> dict[str, ca.Function]:
    """file_velocities(q, theta) and initial_guess(theta) of an IR whose bodies' r0, p0, r_dot0
    and omega0 are expressions of theta (or numbers)."""
    q, bodies = x.q, ir.bodies
    velocities = [constant(b.r_dot0) for b in bodies]
    velocities += [0.5 * euler.e_matrix(x.p(k)).T @ constant(b.omega0)
                   for k, b in enumerate(bodies)]
    pose = [constant(b.r0) for b in bodies] + [constant(b.p0) for b in bodies]
    empty = ca.SX(0, 1)
    return {"file_velocities": _function("file_velocities", {"q": q, "theta": theta},
                                         {"q_dot": ca.vertcat(*velocities) if bodies
                                          else empty}),
            "initial_guess": _function("initial_guess", {"theta": theta},
                                       {"q": ca.vertcat(*pose) if bodies else empty})}


def _bound(function: ca.Function, theta: ca.SX, d) -> ca.Function:
    """A bundle function (trailing input d) with theta in place of d = d(theta)."""
    inputs = [ca.SX.sym(function.name_in(k), function.sparsity_in(k))
              for k in range(function.n_in() - 1)]
    return ca.Function(function.name(), [*inputs, theta], function.call([*inputs, d]),
                       [*function.name_in()[:-1], "theta"], function.name_out())


def _with_offsets(ir: ModelIR, velocity_offsets: dict) -> ModelIR:
    bodies = tuple(replace(b, **{field: constant(getattr(b, field)) + vector
                                 for (name, field), vector in velocity_offsets.items()
                                 if name == b.name}) for b in ir.bodies)
    return replace(ir, bodies=bodies)


def _over_data(split, names: tuple[str, ...], velocities) -> dict[str, ca.Function]:
    """The bundle's and the start functions over [d; theta] (theta: the velocity offsets; the
    file parameters reach the functions only through d)."""
    both = ca.vertcat(split.symbols, ca.SX.sym("offsets", len(names)))
    symbols = {n: both[split.values.size + k] for k, n in enumerate(names)}
    bundle = build_functions(split.ir, split.symbols)
    functions = {name: _bound(bundle[name], both, split.symbols) for name in BUNDLE}
    ir = _with_offsets(split.ir, offsets(velocities, symbols))
    start = _start(ir, Coordinates.create(ir.n_bodies), both)
    return functions | start


def data_system(model: ResolvedModel, names: Iterable[str]) -> ParametricSystem:
    """The "data" method (module docstring): theta through the model data d."""
    names = tuple(dict.fromkeys(names))
    parameters, velocities = classify(model, names)
    derivative = lowering.derivative(model, parameters)
    split = derivative.split
    theta = ca.SX.sym("theta", len(names))
    values = np.array([model.parameters.get(n, 0.0) for n in names], float)
    chosen = [names.index(n) for n in parameters]
    moved = ca.sparsify(ca.DM(derivative.jacobian)) @ (theta[chosen] - values[chosen]) \
        if chosen else ca.DM.zeros(split.values.size)
    d = ca.DM(split.values) + moved
    over = _over_data(split, names, velocities)
    functions = {name: _bound(f, theta, ca.vertcat(d, theta)) for name, f in over.items()}
    return ParametricSystem(functions, build_functions(lower(model)), names, values, "data",
                            dict(zip(parameters, derivative.error.tolist(), strict=True)))


@dataclass(frozen=True)
class DataInputs:
    """A system whose theta is [d_moving; theta] (the entries of the model data the parameters
    move, then the names' values; the other entries are constants), exact at every theta
    through `data` (model_data.ModelData: keep it alive while `inputs` is used)."""

    system: ParametricSystem
    data: ModelData
    inputs: ca.Function  # theta -> [d(theta)[moving]; theta] (MX, through the callback)


def data_inputs(model: ResolvedModel, names: Iterable[str]) -> DataInputs:
    """The model over its data d for evaluations at other theta values (estimation), any
    parameter that keeps the structure, geometry and composed models included. Only the
    entries that move with the parameters (lowering.derivative's stencils) are inputs, so
    IDAS carries only those as parameters."""
    names = tuple(dict.fromkeys(names))
    parameters, velocities = classify(model, names)
    values = np.array([model.parameters.get(n, 0.0) for n in names], float)
    derivative = lowering.derivative(model, parameters)
    split, moving = derivative.split, np.flatnonzero(derivative.moved)
    over = _over_data(split, names, velocities)
    entries = ca.SX.sym("d_moving", moving.size)
    d = ca.SX(ca.DM(split.values))
    for k, index in enumerate(moving):
        d[int(index)] = entries[k]
    velocity = ca.SX.sym("offsets", len(names))
    inner = ca.vertcat(entries, velocity)
    functions = {name: _bound(f, inner, ca.vertcat(d, velocity)) for name, f in over.items()}
    labels = (*(f"d[{k}]" for k in moving), *names)
    system = ParametricSystem(functions, build_functions(lower(model)), labels,
                              np.concatenate([split.values[moving], values]), "data")
    data = ModelData(model, parameters)
    theta = ca.MX.sym("theta", len(names))
    chosen = [names.index(n) for n in parameters]
    moved = data(theta[chosen])[moving.tolist()] if chosen else ca.MX(0, 1)
    return DataInputs(system, data, ca.Function("data_inputs", [theta],
                                                [ca.vertcat(moved, theta)], ["theta"],
                                                ["theta_d"]))


def auto_method(model: ResolvedModel, names: Iterable[str]) -> str:
    """"symbolic" unless a parameter among `names` moves the geometry or the model is
    composed, then "data"."""
    return "data" if geometry_moved(model, classify(model, names)[0]) else "symbolic"


def parametric_system(model: ResolvedModel, names: Iterable[str] = (),
                      method: str = "symbolic") -> ParametricSystem:
    """The model's system functions with `names` (parameters, `<body>.vx`..) as `theta`;
    `method` "auto": auto_method's choice (module docstring)."""
    if method not in METHODS:
        raise UsageError(f"method '{method}' is not one of {', '.join(METHODS)}")
    names = tuple(dict.fromkeys(names))
    if method == "auto":
        method = auto_method(model, names)
    if method == "data":
        return data_system(model, names)
    symbolic = symbolic_model(model, names)
    return ParametricSystem(build_parametric(symbolic), build_functions(symbolic.numeric),
                            symbolic.names, symbolic.values)
