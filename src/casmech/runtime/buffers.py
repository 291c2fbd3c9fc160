"""Calls of casadi Functions with NumPy arrays in and out, through Function.buffer: inputs are
read from and outputs written into NumPy memory, without the element-by-element conversion of
a returned DM (np.array(DM) costs more than evaluating a mapped prescribed step over 10^5 rows).
Functions with a sparse input or output are called the ordinary way. A buffered evaluation is
a solver call a signal may stop at once (runtime.cancel.solving); the errors.Interrupted it
then raises carries in `outputs` what the call had written (an integrator writes its outputs
grid point by grid point; the rest NaN), so the rows computed before the signal are kept. Only
a function a signal can stop midway (`interruptible`: casadi's solvers) has its outputs set
to NaN before each call.

A call's NumPy memory is bound to the buffer once (BOUND_ENTRIES): each call copies its inputs
in and its outputs out, since binding an argument costs about as much as evaluating a small
compiled function. So one BufferedCall is not to be called from two threads at once (the
buffer it wraps never was)."""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.errors import Interrupted
from casmech.runtime import cancel
from casmech.runtime.memo import kept

# Functions whose inputs and outputs hold up to this many numbers keep them bound to the buffer
# (BufferedCall); larger ones (a large tree's rows over a block) bind them per call, so that
# kept calls do not hold their memory.
BOUND_ENTRIES = 1 << 16
# Function classes whose evaluation no signal stops (casadi checks for interrupts in its
# solvers only): a call of such functions alone leaves no output unwritten to mark with NaN.
UNINTERRUPTED = frozenset({"SXFunction", "MXFunction", "External", "Map"})


def interruptible(function: ca.Function) -> bool:
    """Whether a signal may stop an evaluation of `function` midway: it is, or calls, a
    function of a class not in UNINTERRUPTED (an integrator, a rootfinder, a solver)."""
    return function.class_name() not in UNINTERRUPTED or any(
        f.class_name() not in UNINTERRUPTED for f in function.find_functions())


class BufferedCall:
    """function(*arrays) -> tuple of dense NumPy arrays, one per output (fresh arrays, which
    the next call does not touch). An argument None stands for zeros. `stoppable`: whether a
    signal may stop an evaluation midway (default: interruptible(function))."""

    def __init__(self, function: ca.Function, stoppable: bool | None = None):
        self.function = function
        self.stoppable = interruptible(function) if stoppable is None else stoppable
        n_in, n_out = function.n_in(), function.n_out()
        self.dense = all(function.sparsity_in(i).is_dense() for i in range(n_in)) and \
            all(function.sparsity_out(i).is_dense() for i in range(n_out))
        self.shapes_in = [function.size_in(i) for i in range(n_in)]
        self.shapes_out = [function.size_out(i) for i in range(n_out)]
        self._bound: tuple[list[np.ndarray], list[np.ndarray]] | None = None
        if self.dense:
            self.buffer, self.evaluate = function.buffer()
            entries = sum(r * c for r, c in (*self.shapes_in, *self.shapes_out))
            if entries <= BOUND_ENTRIES:
                self._bound = self._bind()
        self._zero = [False] * n_in  # bound inputs known to hold zeros
        # the inputs and outputs that hold numbers (an empty one is bound and never touched)
        self._live_in = [i for i, (r, c) in enumerate(self.shapes_in) if r * c]
        self._live_out = [i for i, (r, c) in enumerate(self.shapes_out) if r * c]

    def _bind(self) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """Input and output arrays bound to the buffer: casadi stores a dense matrix column by
        column, so each is the C-ordered transpose of its matrix."""
        inputs = [np.zeros(shape[::-1]) for shape in self.shapes_in]
        outputs = [np.empty(shape[::-1]) for shape in self.shapes_out]
        for i, a in enumerate(inputs):
            self.buffer.set_arg(i, memoryview(a.reshape(-1)))
        for i, out in enumerate(outputs):
            self.buffer.set_res(i, memoryview(out.reshape(-1)))
        return inputs, outputs

    def __call__(self, *args) -> tuple[np.ndarray, ...]:
        if not self.dense:
            outputs = self.function(*(0 if a is None else a for a in args))
            outputs = outputs if isinstance(outputs, tuple) else (outputs,)
            return tuple(np.array(o, float) for o in outputs)
        if len(args) != len(self.shapes_in):
            raise TypeError(f"{self.function.name()} takes {len(self.shapes_in)} arguments, "
                            f"{len(args)} given")
        bound = self._bound is not None
        inputs, outputs = self._bound if bound else self._bind()
        zero = self._zero
        for i in self._live_in:
            a = args[i]
            if a is None:  # a bound input is zeroed once, a new one is zeros
                if bound and not zero[i]:
                    inputs[i].fill(0.0)
                    zero[i] = True
                continue
            shape = self.shapes_in[i]
            np.copyto(inputs[i], (a if type(a) is np.ndarray and a.shape == shape
                                  else np.reshape(a, shape)).T)
            zero[i] = False
        if self.stoppable:
            for i in self._live_out:
                outputs[i].fill(np.nan)  # what an interrupted call did not write
        cancel.arm()  # a signal may stop an integrator here (runtime.cancel.solving)
        try:
            self.evaluate()
        except RuntimeError as error:
            try:
                cancel.check(error)  # the signal that stopped it, not a failure
            except Interrupted as interrupted:
                interrupted.outputs = tuple((out.copy() if bound else out).T
                                            for out in outputs)
                raise
            raise
        finally:
            cancel.disarm()
        if not bound:
            return tuple(out.T for out in outputs)
        fresh = list(outputs)  # an empty output holds nothing the next call could change
        for i in self._live_out:
            fresh[i] = outputs[i].copy()
        return tuple(out.T for out in fresh)


class NamedCall:
    """function(name=array, ...) -> {output name: dense array} through a BufferedCall, the
    inputs not given zero: how a kept integrator is called, its outputs over the grid written
    into NumPy (docs/decisions/output-blocks.md). A solver failure raises the RuntimeError the
    ordinary call raises (its text without casadi's "Error in Function::call" lines)."""

    def __init__(self, function: ca.Function):
        self.function, self.call = function, BufferedCall(function)
        self.names_in, self.names_out = function.name_in(), function.name_out()
        # (the inputs of a call, what a caller derived from its statistics), kept by the caller
        self.derived: tuple | None = None

    def __call__(self, **inputs) -> dict[str, np.ndarray]:
        args = [inputs.get(name) for name in self.names_in]
        try:
            return dict(zip(self.names_out, self.call(*args), strict=True))
        except Interrupted as interrupted:  # its outputs by name too
            if getattr(interrupted, "outputs", None) is not None:
                interrupted.outputs = dict(zip(self.names_out, interrupted.outputs,
                                               strict=True))
            raise

    def stats(self) -> dict:
        """The statistics of the last call (kept by the buffer's own memory), {} before one."""
        try:
            return self.call.buffer.stats() if self.call.dense else self.function.stats()
        except RuntimeError:  # no call yet
            return {}


# Columns per mapped call. casadi builds a Map in time growing with its length times the
# function's size, so columns are evaluated in blocks of up to BLOCK, and of at most
# MAP_ENTRIES input and output numbers, through kept maps (one per block length and set of
# shared arguments: the full block's and the lengths of shorter blocks, at most KEPT_MAPS);
# a call's own cost is small beside its columns' (docs/decisions/output-blocks.md).
BLOCK = 256
MAP_ENTRIES = 131_072
KEPT_MAPS = 8


class ColumnCall:
    """function evaluated at every column of its arguments (each with one column per
    evaluation, or one for all; an input of w columns takes w per evaluation), in blocks of
    up to BLOCK evaluations and MAP_ENTRIES numbers: per output, the evaluations' outputs side
    by side. An argument shared by all is passed once per call, to a map that hands it to
    every evaluation (casadi's map with reduce_in), not repeated in NumPy."""

    def __init__(self, function: ca.Function):
        self.function = function
        self.widths = [function.size2_in(k) for k in range(function.n_in())]
        # by (block length, the indices of the arguments shared by its evaluations)
        self.maps: dict[tuple[int, tuple[int, ...]], BufferedCall] = {}
        self.stoppable = interruptible(function)
        entries = sum(function.nnz_in(k) for k in range(function.n_in())) + sum(
            function.nnz_out(k) for k in range(function.n_out()))
        self.block = max(1, min(BLOCK, MAP_ENTRIES // max(entries, 1)))

    def _map(self, count: int, shared: tuple[int, ...]) -> BufferedCall:
        """The kept map over `count` evaluations, the arguments `shared` passed once."""
        shared = shared if count > 1 else ()

        def build() -> BufferedCall:
            function = self.function
            mapped = function.map(f"shared_{function.name()}", "serial", count, list(shared),
                                  []) if shared else function.map(count)
            return BufferedCall(mapped, self.stoppable)

        return kept(self.maps, (count, shared), build, KEPT_MAPS)

    def __call__(self, *arguments) -> tuple[np.ndarray, ...]:
        arguments = [self._matrix(np.asarray(a, float), k) for k, a in enumerate(arguments)]
        shared, counts = [], []
        for a, w in zip(arguments, self.widths, strict=True):
            shared.append(a.shape[1] == w)
            if not shared[-1]:
                counts.append(a.shape[1] // max(w, 1))
        count = max(counts, default=1)
        if count == 0:
            return tuple(np.zeros((self.function.size1_out(k), 0))
                         for k in range(self.function.n_out()))
        indices = tuple(k for k, one in enumerate(shared) if one)

        def block(start: int, size: int) -> tuple[np.ndarray, ...]:
            """The evaluations start .. start + size in one mapped call (an argument that is
            that block whole passed as it is)."""
            return self._map(size, indices)(*(
                a if one or (start == 0 and a.shape[1] == size * w)
                else a[:, start * w:(start + size) * w]
                for a, w, one in zip(arguments, self.widths, shared, strict=True)))

        if count <= self.block:
            return block(0, count)
        blocks = [block(start, min(self.block, count - start))
                  for start in range(0, count, self.block)]
        return tuple(np.concatenate(parts, axis=1) for parts in zip(*blocks, strict=True))

    def _matrix(self, argument: np.ndarray, k: int) -> np.ndarray:
        """A 2-D argument as given; a vector as one column (shared by every evaluation)."""
        if argument.ndim == 2:
            return argument
        rows = self.function.size1_in(k)
        return argument.reshape(rows, -1) if rows else np.zeros((0, self.widths[k]))

