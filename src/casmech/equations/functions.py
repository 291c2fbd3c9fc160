"""The named casadi.Function bundle that every analysis consumes.

Interpreted (SX) and compiled bundles are interchangeable: analyses only call
`bundle[name](...)` and read the metadata below. Both are equations.system's functions: the
interpreted bundle evaluates its kernels inline (build_functions), the one code generation
compiles maps them (mapped_functions).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, MutableMapping
from dataclasses import field
from pathlib import Path

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.equations.evaluation import Evaluation, is_inline
from casmech.model.ir import GROUND_INDEX, ModelIR, RowInfo

# (equations.system, the builder, is imported by the functions that build: a warm compiled run
# loads its functions and builds none)


@record
class JointMeta:
    """A joint as the bundle describes it: name, type, its rows, its bodies' names and its
    source."""

    name: str
    type: str
    rows: range
    body_i: str
    body_j: str
    source: object = None


@record
class Library:
    """The parametric library a compiled bundle is bound to: its folder and the structure's
    signature it was built for (backends.rebind binds it to other values)."""

    folder: Path
    signature: str | None


@record(eq=False)
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
    # the parametric library the functions are bound to (codegen.parametric), None: none
    parametric: Library | None = field(default=None, repr=False)
    # the cache key of the library its compiled functions and `ir` came from (backends.load),
    # which keys what is compiled for it later (runtime.joint_dynamics); a bundle made over
    # another IR must not carry it
    library_key: str | None = field(default=None, repr=False)

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
        # name -> the same function built mapped (MX) over the same IR, when the builder can
        self.mapped: Callable[[str], ca.Function] | None = None
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


def _bundle(ir: ModelIR, functions, mode: str | None = None) -> SystemFunctions:
    names = tuple(b.name for b in ir.bodies)

    def body_name(k: int) -> str:
        return "ground" if k == GROUND_INDEX else names[k]

    joints = tuple(JointMeta(j.name, j.type, j.rows, body_name(j.body_i), body_name(j.body_j),
                             j.source) for j in ir.joints)
    return SystemFunctions(functions, names, joints, tuple(ir.row_info()), ir, mode=mode)


def build_functions(ir: ModelIR, data: ca.SX | None = None) -> SystemFunctions:
    """The interpreted bundle: every function inline (SX), built when first used
    (LazyFunctions). `data`: for a symbolic IR (model.parametric.split), its symbols, every
    function's trailing input "d"."""
    from casmech.equations import system

    shared = system.System(ir, Evaluation.of(True, data, ir.n_bodies))
    groups = [((name,), lambda name=name: [system.function(shared, name)])
              for name in system.DEFINITIONS]
    lazy = LazyFunctions(groups)
    mapped: list[system.System] = []  # the mapped System, made on first use

    def mapped_function(name: str) -> ca.Function:
        if not mapped:
            mapped.append(system.System(ir, Evaluation.of(False, data)))
        return system.function(mapped[0], name)

    lazy.mapped = mapped_function
    return _bundle(ir, lazy, "interpreted")


def results_terms(functions: SystemFunctions) -> dict[str, ca.Function]:
    """The functions a results row reads (system.RESULTS, then phi), by name: the bundle's own;
    for an interpreted bundle of more bodies than WHERE_INLINE["results"], the results-only
    ones it has not built or been given built mapped, then expanded to SX (each kernel's
    instances unrolled by CasADi, not by the builder's Python)."""
    from casmech.equations import system

    bundle = functions.functions
    mapped = isinstance(bundle, LazyFunctions) and bundle.mapped is not None and \
        not is_inline("results", functions.n_bodies)

    def term(name: str) -> ca.Function:
        if mapped and name not in bundle.given and name not in bundle._built:
            return bundle.mapped(name).expand()
        return bundle[name]

    return {name: term(name) for name in system.RESULTS} | {"phi": bundle["phi"]}


def mapped_functions(ir: ModelIR, data: ca.SX | None = None) -> dict[str, ca.Function]:
    """name -> MX Function of every system function, its kernels mapped over their instances:
    the bundle code generation compiles. `data`: as build_functions'."""
    from casmech.equations import system

    shared = system.System(ir, Evaluation.of(False, data))
    return {name: system.function(shared, name) for name in system.DEFINITIONS}
