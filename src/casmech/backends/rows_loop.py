"""A compiled function evaluated over rows by C loops (c/casmech_rows.c, loaded by
backends.rk_library.rows_driver), calling it at its C entry point (rk_library.Entry: a function
casmech loaded from a library, or bound such a function to the model data) as casmech_rk.c
calls the ODE: what casadi's map over columns gives, without the map's bookkeeping per
evaluation and the copies of its buffers. Every input and output row-major: row i of input k
is its i-th row (or the same vector for every row), row i of output k its i-th row. A function
made of a chain of compiled parts (backends.split, recorded here by `chained`) is evaluated part
by part, each over all the rows, in the same C call."""

from __future__ import annotations

import ctypes
import weakref

import casadi as ca
import numpy as np

from casmech.backends import external_record, rk_library


class RowsCall:
    """function(rows, *inputs) -> one (rows, nnz_out(k)) array per output, fresh each call.
    An input (one per input of the function, a bound function's d excepted) is None (zeros),
    a vector of nnz_in(k) numbers (the same for every row) or a (rows, nnz_in(k)) array (of a
    scalar input, also a vector of one number a row). The outputs of one call are views of
    one array. `entries`: the function's own entry, or its chain's parts' (chained; their
    shared values in buffers of this call, kept between calls). Not to be called from two
    threads at once (the functions' work vectors are one)."""

    def __init__(self, run, entries: list[rk_library.Entry], function: ca.Function | None = None):
        first, last = entries[0].function, entries[-1].function
        self.run, self.entries = run, entries
        self.function = function if function is not None else first
        self.n_in, self.n_out = first.n_in(), last.n_out()
        self.sizes_in = [first.nnz_in(k) for k in range(self.n_in)]
        self.sizes_out = [last.nnz_out(k) for k in range(self.n_out)]
        offsets = np.cumsum([0, *self.sizes_out]).tolist()
        self.spans = list(zip(offsets[:-1], offsets[1:], strict=True))  # in one array a row
        self.total = offsets[-1]
        # (rows, each output's shape and byte offset in the one array of a call of that many)
        self.layout: tuple[int, list] = (-1, [])
        # the fixed inputs (a bound function's d) read at the same address by every row; the
        # caller gives the others
        fixed = entries[0].fixed
        self.given = [k for k in range(self.n_in) if k not in fixed]
        self.in_p = (ctypes.c_void_p * max(self.n_in, 1))()
        # per input: the vector every row read last call where it was given as it is (an
        # array of its own shape, float, contiguous: a start's signs, the loops' mask), held
        # here so that its address stays its own; the same object given again is read at the
        # address set then (its values read by the call, as any input's)
        self.shared_inputs: list[np.ndarray | None] = [None] * max(self.n_in, 1)
        for k, values in fixed.items():
            self.in_p[k] = values.ctypes.data
        self.out_p = (ctypes.c_void_p * max(self.n_out, 1))()
        self.in_stride = np.zeros(max(self.n_in, 1), np.int64)
        self.out_stride = np.array(self.sizes_out or [0], np.int64)
        # each part but the last: its shared values a row, their buffer (rows x size)
        self.shared_size = np.array([e.function.nnz_out(0) for e in entries[:-1]] or [0],
                                    np.int64)
        self.shared_p = (ctypes.c_void_p * max(len(entries) - 1, 1))()
        self.shared: np.ndarray = np.empty(0)
        self.shared_rows = -1  # the rows the shared pointers are set for
        self.parts = (rk_library.Function * len(entries))(*(e.struct for e in entries))
        self.tail = (self.n_in, ctypes.addressof(self.in_p), self.in_stride.ctypes.data,
                     ctypes.addressof(self.shared_p), self.shared_size.ctypes.data,
                     self.n_out, ctypes.addressof(self.out_p), self.out_stride.ctypes.data)

    def __call__(self, rows: int, *inputs) -> tuple[np.ndarray, ...]:
        if len(inputs) != len(self.given):
            raise TypeError(f"{self.function.name()} takes {len(self.given)} inputs, "
                            f"{len(inputs)} given")
        kept = []  # the arrays the pointers point into, alive through the call
        shared = self.shared_inputs
        for k, given in zip(self.given, inputs, strict=True):
            size = self.sizes_in[k]
            if given is None or not size:
                self.in_p[k] = shared[k] = None
                continue
            if given is shared[k] and given.shape == (size,):  # its address already set
                self.in_stride[k] = 0
                continue
            a = np.ascontiguousarray(given, float)
            if a.shape == (rows, size) or (size == 1 and a.shape == (rows,)):
                self.in_stride[k] = size
                kept.append(a)
            elif a.shape == (size,):
                self.in_stride[k] = 0
                kept.append(a)
            else:
                raise ValueError(f"{self.function.name()}'s input {k} has shape {a.shape}, "
                                 f"not ({rows}, {size}) or ({size},)")
            shared[k] = a if a is given and self.in_stride[k] == 0 else None
            self.in_p[k] = _address(a)
        if rows != self.shared_rows and len(self.entries) > 1:
            self._share(rows)
        layout = self.layout
        if layout[0] != rows:
            layout = self.layout = (rows, [((rows, b - a), 8 * rows * a) for a, b in self.spans])
        out = np.empty(rows * self.total)
        base = _address(out)
        for k, (_, offset) in enumerate(layout[1]):
            self.out_p[k] = base + offset
        failed = self.run(len(self.entries), self.parts, rows, *self.tail)
        if failed:
            raise RuntimeError(f"{self.function.name()} failed to evaluate at row {failed - 1}")
        return tuple([np.ndarray(shape, float, out, offset) for shape, offset in layout[1]])

    def _share(self, rows: int) -> None:
        """The shared values' buffers for `rows` rows (grown when short) and their pointers
        (called when the rows change)."""
        sizes = self.shared_size.tolist()
        if self.shared.size < rows * sum(sizes):
            self.shared = np.empty(rows * sum(sizes))
        base = self.shared.ctypes.data
        for k, size in enumerate(sizes):
            self.shared_p[k] = base
            base += 8 * rows * size
        self.shared_rows = rows


def _address(a: np.ndarray) -> int:
    """The address of a C-contiguous array's data: through a ctypes view of its buffer (less
    than half of `ndarray.ctypes`' cost), or `ndarray.ctypes` where that takes none (a
    read-only or empty array)."""
    try:
        return ctypes.addressof(ctypes.c_char.from_buffer(a))
    except (TypeError, ValueError):
        return a.ctypes.data


# a chained function's key (Function.__hash__, as backends.external_record keys its entries)
# -> (a wrapper of its own, keeping its object alive, its parts)
_CHAINS: dict[int, tuple[ca.Function, tuple[ca.Function, ...]]] = {}


def chained(function: ca.Function, chain) -> ca.Function:
    """`function` (backends.split.joined of `chain`, compiled parts casmech loaded), recorded as
    the chain's parts called in turn, for rows_call; the record lasts as long as this wrapper
    of it."""
    key = function.__hash__()
    entry = (ca.Function(function), tuple(chain))
    _CHAINS[key] = entry
    finalizer = weakref.finalize(function, _forget, key, entry)
    finalizer.atexit = False
    return function


def _forget(key: int, entry) -> None:
    if _CHAINS.get(key) is entry:  # not one recorded since for the same object
        del _CHAINS[key]


def rows_call(function: ca.Function) -> RowsCall | None:
    """A RowsCall of `function` where it, or each part of the chain it was recorded as
    (chained), has a C entry point (casmech loaded it from a library, or bound such a
    function to the model data: backends.external_record; a chain's parts not bound), its
    inputs and outputs are dense and the loop's library is there; else None."""
    chain = _CHAINS.get(function.__hash__())
    parts = chain[1] if chain is not None else (function,)
    entries = []
    for part in parts:
        found = rk_library.unbound(part)
        if found is None or (chain is not None and found[1]):
            return None
        inner, fixed = found
        path = external_record.library(inner)
        if path is None or not all(inner.sparsity_in(k).is_dense()
                                   for k in range(inner.n_in())) or not all(
                inner.sparsity_out(k).is_dense() for k in range(inner.n_out())):
            return None
        entries.append((inner, path, fixed))
    run = rk_library.rows_driver()
    if run is None:
        return None
    try:
        return RowsCall(run, [rk_library.Entry(*e) for e in entries],
                        function if chain is not None else None)
    except (AttributeError, OSError, ValueError):
        return None
