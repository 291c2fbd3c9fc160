"""The named casadi.Function bundle that every analysis consumes.

Interpreted (SX) and compiled bundles are interchangeable: analyses only call
`bundle[name](...)` and read the metadata below.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from casmech.compiler import body, contact, eom, romega
from casmech.compiler.assemble import build_constraints
from casmech.compiler.ir import GROUND_INDEX, ModelIR, RowInfo


@dataclass(frozen=True)
class JointMeta:
    name: str
    type: str
    rows: range
    body_i: str
    body_j: str
    source: object = None


@dataclass(frozen=True)
class SystemFunctions:
    """casadi.Functions by name plus what analyses need to know about the model."""

    functions: dict[str, ca.Function]
    body_names: tuple[str, ...]
    joints: tuple[JointMeta, ...]
    rows: tuple[RowInfo, ...]
    ir: ModelIR = field(repr=False)
    # what analyses derive from the bundle once and reuse (e.g. the joint formulation's system)
    derived: dict = field(default_factory=dict, repr=False, compare=False)
    # a compiled parametric bundle (codegen.parametric): the model data `ir` was lowered to,
    # bound in every function but the DAE residuals, which take it after their own p
    data: np.ndarray | None = field(default=None, repr=False, compare=False)

    def __getitem__(self, name: str) -> ca.Function:
        return self.functions[name]

    def evaluate(self, name: str, *args) -> list[np.ndarray]:
        """Call a function numerically; every output as a dense numpy array."""
        return [np.array(out.full()) for out in _as_list(self.functions[name](*args))]

    def matrix(self, name: str, *args) -> np.ndarray:
        """The first output of a function as a dense 2-D array."""
        return self.evaluate(name, *args)[0]

    def vector(self, name: str, *args) -> np.ndarray:
        """The first output of a function as a flat array."""
        return self.evaluate(name, *args)[0].ravel()

    @property
    def n_bodies(self) -> int:
        return len(self.body_names)

    @property
    def n_coordinates(self) -> int:
        return 7 * len(self.body_names)

    @property
    def n_rows(self) -> int:
        return len(self.rows)

    @property
    def n_joint_rows(self) -> int:
        """Rows of phi that are joint constraints (not Euler-parameter normalization)."""
        return sum(row.kind != "normalization" for row in self.rows)


def _as_list(outputs) -> list:
    return list(outputs) if isinstance(outputs, (tuple, list)) else [outputs]


def _function(name, inputs: dict, outputs: dict) -> ca.Function:
    return ca.Function(name, list(inputs.values()), list(outputs.values()),
                       list(inputs), list(outputs))


def build_functions(ir: ModelIR, data: ca.SX | None = None) -> SystemFunctions:
    """The bundle of a numeric IR; of a symbolic one (compiler.parametric.split) with `data`,
    its symbols, as every function's trailing input "d"."""
    extra = {} if data is None else {"d": data}
    cs = build_constraints(ir)
    x = cs.x
    t, q, q_dot, q_ddot = x.t, x.q, x.q_dot, x.q_ddot
    lam = ca.SX.sym("lam", cs.phi.numel())
    fixed = x.ground_fixed
    mass = eom.mass_matrix(ir, x)
    applied, spring_potential = eom.applied_forces(ir, x)
    kinetic, potential = eom.energy(ir, x, spring_potential)
    force, torque = eom.reactions(ir, x, cs.phi_with_ground, lam)
    rates = [body.global_rates(x.p(k), x.p(k, q_dot), x.p(k, q_ddot)) for k in range(ir.n_bodies)]
    omega, alpha = [w for w, _ in rates], [a for _, a in rates]
    stack = (lambda vs: ca.horzcat(*vs)) if ir.n_bodies else (lambda vs: ca.SX(3, 0))
    definitions = [
        ("phi", {"t": t, "q": q}, {"phi": cs.phi}),
        ("phi_q", {"t": t, "q": q}, {"phi_q": cs.phi_q}),
        ("nu", {"t": t, "q": q}, {"nu": cs.nu}),
        ("gamma", {"t": t, "q": q, "q_dot": q_dot}, {"gamma": cs.gamma}),
        ("variations", {"t": t, "q": q}, {"phi_r": cs.phi_r, "pi_bar": cs.pi_bar}),
        ("phi_scaled", {"t": t, "q": q, "s": cs.scale},
         {"phi": cs.phi_scaled, "phi_q": cs.phi_q_scaled}),
        ("mass_matrix", {"q": q}, {"mass_matrix": mass}),
        ("generalized_forces", {"t": t, "q": q, "q_dot": q_dot},
         {"generalized_forces": fixed(applied + eom.quadratic_velocity(ir, x))}),
        ("energy", {"t": t, "q": q, "q_dot": q_dot},
         {"kinetic": fixed(kinetic), "potential": fixed(potential)}),
        ("reactions", {"t": t, "q": q, "q_dot": q_dot, "lam": lam},
         {"force": fixed(force), "torque": fixed(torque)}),
        ("body_rates", {"q": q, "q_dot": q_dot, "q_ddot": q_ddot},
         {"omega": stack(omega), "alpha": stack(alpha)}),
        ("element_outputs", {"t": t, "q": q, "q_dot": q_dot},
         {"values": fixed(contact.element_outputs(ir, x))}),
    ]
    definitions += romega.definitions(ir, cs)
    functions = [_function(name, inputs | extra, outputs) for name, inputs, outputs in definitions]
    names = tuple(b.name for b in ir.bodies)

    def body_name(k: int) -> str:
        return "ground" if k == GROUND_INDEX else names[k]

    joints = tuple(JointMeta(j.name, j.type, j.rows, body_name(j.body_i), body_name(j.body_j),
                             j.source) for j in ir.joints)
    return SystemFunctions({f.name(): f for f in functions}, names, joints,
                           tuple(ir.row_info()), ir)
