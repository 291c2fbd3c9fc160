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
from parametric.data).
"""

from __future__ import annotations

import hashlib
import threading
from collections.abc import Iterator, Mapping

import casadi as ca
import numpy as np

from casmech.backends.build import Toolchain
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
    """The compiled functions of one IR's joint space (module docstring): `externals` (name ->
    the loaded function, with "d"), `bound` (name -> it with "d" fixed: SIGNATURES' inputs),
    `data()` (the value of "d"); each library built or loaded on first access."""

    def __init__(self, ir: ModelIR, toolchain: Toolchain | None = None):
        self._values, signature = parametric.data(ir)
        tables = hashlib.sha256()
        table_digest(ir, tables)
        self._content = {"kind": "joint_space", "structure": signature,
                         "tables": tables.hexdigest()}
        self._ir, self._toolchain = ir, toolchain
        self._symbolic: tuple | None = None
        self._loaded: dict[str, ca.Function] = {}
        self._data: np.ndarray | None = None
        self._lock = threading.RLock()
        self.externals = _Lazy(self._external)
        self.bound = _Lazy(lambda name: bound(self._external(name), self.data()))

    def data(self) -> np.ndarray:
        """The value of "d" for this IR's numbers (joint_data of the first library loaded)."""
        if self._data is None:
            self._external(next(iter(SIGNATURES)))
        return self._data

    def _external(self, name: str) -> ca.Function:
        with self._lock:
            if name not in self._loaded:
                library = compile_keyed({**self._content, "function": name},
                                        lambda: self._make(name), toolchain=self._toolchain)
                if self._data is None:
                    self._data = np.array(library[JOINT_DATA](self._values), float).ravel()
                self._loaded[name] = library[name]
            return self._loaded[name]

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
