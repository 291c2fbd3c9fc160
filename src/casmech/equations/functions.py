"""The named casadi.Function bundle that every analysis consumes.

Interpreted (SX) and compiled bundles are interchangeable: analyses only call
`bundle[name](...)` and read the metadata below.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, MutableMapping
from dataclasses import dataclass, field
from functools import cached_property

import casadi as ca
import numpy as np

from casmech.equations import body, contact, eom, romega
from casmech.equations.assemble import build_constraints
from casmech.model.ir import GROUND_INDEX, ModelIR, RowInfo


@dataclass(frozen=True)
class JointMeta:
    name: str
    type: str
    rows: range
    body_i: str
    body_j: str
    source: object = None


@dataclass(frozen=True, eq=False)
class SystemFunctions:
    """casadi.Functions by name plus what analyses need to know about the model. Immutable:
    what analyses derive from it and reuse lives in a runtime.workspace.Workspace. Compared
    and hashed by identity (a workspace is associated with one bundle)."""

    functions: Mapping[str, ca.Function]  # a dict, or an interpreted build's LazyFunctions
    body_names: tuple[str, ...]
    joints: tuple[JointMeta, ...]
    rows: tuple[RowInfo, ...]
    ir: ModelIR = field(repr=False)
    # a compiled parametric bundle (codegen.parametric): the model data `ir` was lowered to,
    # bound in every function but the DAE residuals, which take it after their own p
    data: np.ndarray | None = field(default=None, repr=False)
    # "interpreted" or "compiled" when its builder knows (backends.load.mode_of tells otherwise)
    mode: str | None = None
    # a parametric library's joint-formulation functions bound to `data` (codegen.parametric;
    # runtime.joint_dynamics takes them), by name
    joint_functions: Mapping[str, ca.Function] | None = field(default=None, repr=False)

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


class LazyFunctions(MutableMapping):
    """An interpreted bundle's functions by name, each group built on first use: a
    joint-coordinate run reads 7 of the 19 (phi, phi_q, nu for the assembly; the results
    row's; docs/decisions/traced-steps.md). `groups`: (the names a group makes, or None when
    only building it tells them, and its maker () -> Functions), in the bundle's order."""

    def __init__(self, groups: list[tuple[tuple[str, ...] | None, Callable[[], list]]]):
        self._groups = list(groups)
        self._built: dict[str, ca.Function] = {}
        self._group_of = {name: k for k, (names, _) in enumerate(groups) for name in names or ()}
        self.given: dict[str, ca.Function] = {}  # set by callers (the rest: SX, built here)
        self._done: set[int] = set()  # groups built

    def _build(self, k: int) -> None:
        if k in self._done:
            return
        self._done.add(k)
        functions = self._groups[k][1]()
        for function in functions:  # (a function set in its place is kept)
            self._built.setdefault(function.name(), function)
        self._groups[k] = (tuple(f.name() for f in functions), self._groups[k][1])
        self._group_of.update((f.name(), k) for f in functions)

    def _name_all(self) -> None:
        """Build the groups whose names are not known yet."""
        for k, (names, _) in enumerate(self._groups):
            if names is None:
                self._build(k)

    def __getitem__(self, name: str) -> ca.Function:
        if name not in self._built:
            if name not in self._group_of:
                self._name_all()
            self._build(self._group_of[name])  # a KeyError for a name no group makes
        return self._built[name]  # (a KeyError for a name deleted from a built group)

    def __setitem__(self, name: str, function: ca.Function) -> None:
        """Add or replace a function (codegen adds prescribed_step)."""
        if name not in self:
            self._groups.append(((name,), lambda: []))
            self._group_of[name] = len(self._groups) - 1
            self._done.add(self._group_of[name])
        self._built[name] = self.given[name] = function

    def __delitem__(self, name: str) -> None:
        self[name]  # its group built (a KeyError when no group makes it)
        k = self._group_of.pop(name)
        self._groups[k] = (tuple(n for n in self._groups[k][0] if n != name), self._groups[k][1])
        del self._built[name]
        self.given.pop(name, None)

    def __contains__(self, name) -> bool:
        """Without building the function."""
        if name not in self._group_of:
            self._name_all()
        return name in self._group_of

    def __iter__(self) -> Iterator[str]:
        self._name_all()
        return iter([name for names, _ in self._groups for name in names])

    def __len__(self) -> int:
        self._name_all()
        return sum(len(names) for names, _ in self._groups)


def all_sx(functions: Mapping) -> bool:
    """Whether every function of a bundle's mapping is an SXFunction (a LazyFunctions' own
    are, built or not: it is not built to tell)."""
    given = functions.given if isinstance(functions, LazyFunctions) else functions
    return all(f.is_a("SXFunction") for f in given.values())


def symbol_type(functions: Mapping):
    """ca.SX when every function of the bundle's mapping is SX (calls inline), ca.MX otherwise
    (compiled externals)."""
    return ca.SX if all_sx(functions) else ca.MX


def build_functions(ir: ModelIR, data: ca.SX | None = None) -> SystemFunctions:
    """The bundle of a numeric IR; of a symbolic one (model.parametric.split) with `data`,
    its symbols, as every function's trailing input "d". Each function is built when first
    used (LazyFunctions)."""
    extra = {} if data is None else {"d": data}
    shared = _Shared(ir)

    def group(names: tuple[str, ...] | None, definitions: Callable[[], list]):
        return names, lambda: [_function(name, inputs | extra, outputs)
                               for name, inputs, outputs in definitions()]

    groups = [group((name,), lambda name=name, define=define: [(name, *define(shared))])
              for name, define in DEFINITIONS.items()]
    groups.append(group(None, lambda: romega.definitions(ir, shared.cs)))
    names = tuple(b.name for b in ir.bodies)

    def body_name(k: int) -> str:
        return "ground" if k == GROUND_INDEX else names[k]

    joints = tuple(JointMeta(j.name, j.type, j.rows, body_name(j.body_i), body_name(j.body_j),
                             j.source) for j in ir.joints)
    return SystemFunctions(LazyFunctions(groups), names, joints, tuple(ir.row_info()), ir,
                           mode="interpreted")


class _Shared:
    """What the bundle's functions share, built once when first needed."""

    def __init__(self, ir: ModelIR):
        self.ir = ir

    @cached_property
    def cs(self):
        """The constraint system (equations.assemble)."""
        return build_constraints(self.ir)

    @property
    def x(self):
        return self.cs.x

    @cached_property
    def applied(self) -> tuple:
        """(generalized applied forces, spring potential)."""
        return eom.applied_forces(self.ir, self.x)


def _tq(s: _Shared) -> dict:
    return {"t": s.x.t, "q": s.x.q}


def _tqv(s: _Shared) -> dict:
    return {"t": s.x.t, "q": s.x.q, "q_dot": s.x.q_dot}


def _generalized_forces(s: _Shared) -> tuple:
    forces = s.applied[0] + eom.quadratic_velocity(s.ir, s.x)
    return _tqv(s), {"generalized_forces": s.x.ground_fixed(forces)}


def _energy(s: _Shared) -> tuple:
    kinetic, potential = eom.energy(s.ir, s.x, s.applied[1])
    fixed = s.x.ground_fixed
    return _tqv(s), {"kinetic": fixed(kinetic), "potential": fixed(potential)}


def _reactions(s: _Shared) -> tuple:
    lam = ca.SX.sym("lam", s.cs.phi.numel())
    force, torque = eom.reactions(s.ir, s.x, s.cs.phi_with_ground, lam)
    fixed = s.x.ground_fixed
    return _tqv(s) | {"lam": lam}, {"force": fixed(force), "torque": fixed(torque)}


def _body_rates(s: _Shared) -> tuple:
    x = s.x
    rates = [body.RATES(x.p(k), x.p(k, x.q_dot), x.p(k, x.q_ddot))
             for k in range(s.ir.n_bodies)]
    stack = (lambda vs: ca.horzcat(*vs)) if s.ir.n_bodies else (lambda vs: ca.SX(3, 0))
    return ({"q": x.q, "q_dot": x.q_dot, "q_ddot": x.q_ddot},
            {"omega": stack([w for w, _ in rates]), "alpha": stack([a for _, a in rates])})


# name -> its (inputs, outputs) over the shared pieces (romega's functions follow them)
DEFINITIONS: dict[str, Callable[[_Shared], tuple[dict, dict]]] = {
    "phi": lambda s: (_tq(s), {"phi": s.cs.phi}),
    "phi_q": lambda s: (_tq(s), {"phi_q": s.cs.phi_q}),
    "nu": lambda s: (_tq(s), {"nu": s.cs.nu}),
    "gamma": lambda s: (_tqv(s), {"gamma": s.cs.gamma}),
    "variations": lambda s: (_tq(s), {"phi_r": s.cs.phi_r, "pi_bar": s.cs.pi_bar}),
    "phi_scaled": lambda s: (_tq(s) | {"s": s.cs.scale},
                             {"phi": s.cs.phi_scaled, "phi_q": s.cs.phi_q_scaled}),
    "mass_matrix": lambda s: ({"q": s.x.q}, {"mass_matrix": eom.mass_matrix(s.ir, s.x)}),
    "generalized_forces": _generalized_forces,
    "energy": _energy,
    "reactions": _reactions,
    "body_rates": _body_rates,
    "element_outputs": lambda s: (_tqv(s), {
        "values": s.x.ground_fixed(contact.element_outputs(s.ir, s.x))}),
}
