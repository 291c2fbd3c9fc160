"""The system functions of a model with a `theta` input: the parametric bundle.

The same builders as `casmech.compile` (compiler/assemble.py, compiler/eom.py) run on the symbolic
IR of `symbolic.py`, and every function gets one more input, `theta`. Inertias and gravity enter
the compiler's builders as numeric matrices; both enter the equations linearly, so a symbolic
inertia or gravity is applied exactly as a linear combination of the builders evaluated at unit
entries (the builders stay the single source of the formulas).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from casmech.compiler import eom
from casmech.compiler.assemble import build_constraints
from casmech.compiler.functions import SystemFunctions, build_functions
from casmech.compiler.ir import ModelIR
from casmech.geometry import euler
from casmech.optimal.symbolic import SymbolicModel, symbolic_model
from casmech.schema.resolved import ResolvedModel


@dataclass(frozen=True)
class ParametricSystem:
    """Named casadi.Functions with a `theta` input, and the nominal compiled bundle."""

    functions: dict[str, ca.Function]
    nominal: SystemFunctions  # casmech.compile of the same model (theta = values)
    names: tuple[str, ...]  # what theta holds, in order
    values: np.ndarray  # theta in the file (initial-velocity offsets: 0)

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
    nb = ir.n_bodies
    guess = [ca.vertcat(*[ca.DM(b.r_dot0) if not _is_symbolic(b.r_dot0) else b.r_dot0
                          for b in ir.bodies])]
    guess += [0.5 * euler.e_matrix(x.p(k)).T @ (b.omega0 if _is_symbolic(b.omega0)
                                                 else ca.DM(b.omega0))
              for k, b in enumerate(ir.bodies)]
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
        ("file_velocities", {"q": q, "theta": theta},
         {"q_dot": ca.vertcat(*guess) if nb else ca.SX(0, 1)}),
    ]
    return {name: _function(name, *io) for name, *io in definitions}


def parametric_system(model: ResolvedModel, names: Iterable[str] = ()) -> ParametricSystem:
    """The model's system functions with `names` (parameters, `<body>.vx`..) as `theta`."""
    symbolic = symbolic_model(model, names)
    return ParametricSystem(build_parametric(symbolic), build_functions(symbolic.numeric),
                            symbolic.names, symbolic.values)
