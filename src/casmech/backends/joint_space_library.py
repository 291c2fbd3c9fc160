"""A compiled model's joint space (casmech.joint_space) in C: formulations.joint_space's
functions over model.parametric.split's IR, each compiled when first used, once per model
structure, the values of each parameter set bound when loaded.

Each compiled function takes last the input "d" (the model data with the tree's constants
computed from it: formulations.joint_constants), its outputs dense (runtime.joint_space_calls'
buffers read plain arrays), in a library of its own beside joint_data, which computes that
input from the model data (once per set of values: kept as CasADi's serialization, not
compiled). A library's cache key (backends.library.compile_keyed) is the function's name, the
structure's signature and the model's tables (a table's data is not in the signature): a model
after `set` loads the same libraries, and a cache hit builds no symbolic graph (the values come
from parametric.data). A model compiled with mode "auto" gets each function's library only where
the cache holds it (a lookup whose miss builds nothing), else the function interpreted.
"""

from __future__ import annotations

import hashlib
import threading
from collections.abc import Iterator, Mapping

import casadi as ca
import numpy as np

from casmech.backends.build import Toolchain, available
from casmech.backends.cache import table_digest
from casmech.backends.library import compile_keyed
from casmech.formulations.joint_constants import Constants
from casmech.formulations.joint_space import SIGNATURES, functions
from casmech.formulations.tree import spanning_tree
from casmech.model import parametric
from casmech.model.ir import ModelIR
from casmech.numerics.dense_outputs import dense_outputs

JOINT_DATA = "joint_data"


class CompiledSpace:
    """The compiled functions of one IR's joint space (module docstring), each library built or
    loaded on first access; with `build` False (mode "auto") only loaded where the cache holds
    it, the function's interpreted one (formulations.joint_space over the IR) where it does not.
    `functions`: name -> the function JointSpace.functions holds (a compiled one with "d"
    fixed: SIGNATURES' inputs); `evaluated`: name -> the function its NumPy call evaluates (a
    compiled one with "d"), whose trailing inputs take `trailing(name)`."""

    def __init__(self, ir: ModelIR, toolchain: Toolchain | None = None, build: bool = True):
        self._values, signature = parametric.data(ir)
        tables = hashlib.sha256()
        table_digest(ir, tables)
        self._content = {"kind": "joint_space", "structure": signature,
                         "tables": tables.hexdigest()}
        self._ir, self._toolchain, self._build = ir, toolchain, build
        self._symbolic: tuple | None = None
        self._interpreted: dict[str, ca.Function] | None = None
        self._loaded: dict[str, ca.Function | None] = {}  # None: not in the cache
        self._data: np.ndarray | None = None
        self._lock = threading.RLock()
        self.functions = _Lazy(lambda name: self._either(name, bound))
        self.evaluated = _Lazy(lambda name: self._either(name, lambda external, _: external))

    def trailing(self, name: str) -> tuple:
        """The values of the inputs evaluated[name] takes after SIGNATURES' (its "d")."""
        return () if self._external(name) is None else (self._data,)

    def _either(self, name: str, compiled):
        """compiled(the external, d) where it is loaded, else the interpreted function."""
        external = self._external(name)
        if external is not None:
            return compiled(external, self._data)
        with self._lock:
            if self._interpreted is None:
                self._interpreted = functions(self._ir, spanning_tree(self._ir))
            return self._interpreted[name]

    def _external(self, name: str) -> ca.Function | None:
        with self._lock:
            if name not in self._loaded:
                self._loaded[name] = self._library(name)
            return self._loaded[name]

    def _library(self, name: str) -> ca.Function | None:
        """The loaded function `name` (built on a miss, or with `build` False None)."""
        if not self._build and not available(self._toolchain):
            return None
        try:
            library = compile_keyed({**self._content, "function": name},
                                    (lambda: self._make(name)) if self._build else _refuse,
                                    toolchain=self._toolchain)
        except _Missing:
            return None
        if self._data is None:
            self._data = np.array(library[JOINT_DATA](self._values), float).ravel()
        return library[name]

    def _make(self, name: str):
        """What a library of `name` holds: the function to compile, joint_data to keep (the
        symbolic functions built on the first miss)."""
        if self._symbolic is None:
            split = parametric.split(self._ir)
            constants = Constants(split.symbols)
            made = functions(split.ir, spanning_tree(split.ir), constants=constants)
            self._symbolic = made, constants.function()
        made, data = self._symbolic
        return ({name: dense_outputs(made[name])}, {JOINT_DATA: data},
                self._toolchain or Toolchain())


class _Missing(Exception):
    """A library the cache does not hold, asked for without a build."""


def _refuse():
    """compile_keyed's `make` of a lookup that builds nothing: a miss raises _Missing (before
    anything is written, the lookup's temporary folder removed)."""
    raise _Missing


class _Lazy(Mapping):
    """SIGNATURES' names -> make(name), made on first access."""

    def __init__(self, make):
        self._make, self._made = make, {}

    def __getitem__(self, name: str) -> ca.Function:
        if name not in SIGNATURES:
            raise KeyError(name)
        if name not in self._made:
            self._made[name] = self._make(name)
        return self._made[name]

    def __iter__(self) -> Iterator[str]:
        return iter(SIGNATURES)

    def __len__(self) -> int:
        return len(SIGNATURES)


def bound(function: ca.Function, data: np.ndarray) -> ca.Function:
    """`function` with its trailing "d" fixed to `data`: SIGNATURES' inputs (an MX function
    calling the compiled one)."""
    inputs = function.mx_in()[:-1]
    return ca.Function(function.name(), inputs, function.call([*inputs, ca.DM(data)]),
                       function.name_in()[:-1], function.name_out())
