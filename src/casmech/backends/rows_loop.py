"""A compiled function evaluated over rows by one C loop (c/casmech_rows.c, loaded by
backends.rk_library.rows_driver), calling it at its C entry point (rk_library.Entry: a function
casmech loaded from a library, or bound such a function to the model data) as casmech_rk.c
calls the ODE: what casadi's map over columns gives, without the map's bookkeeping per
evaluation and the copies of its buffers. Every input and output row-major: row i of input k
is its i-th row (or the same vector for every row), row i of output k its i-th row."""

from __future__ import annotations

import ctypes

import casadi as ca
import numpy as np

from casmech.backends import external_record, rk_library


class RowsCall:
    """function(rows, *inputs) -> one (rows, nnz_out(k)) array per output, fresh each call.
    An input (one per input of the function, a bound function's d excepted) is None (zeros),
    a vector of nnz_in(k) numbers (the same for every row) or a (rows, nnz_in(k)) array (of a
    scalar input, also a vector of one number a row). The outputs of one call are views of
    one array. Not to be called from two threads at once (the function's work vectors are
    one)."""

    def __init__(self, run, entry: rk_library.Entry):
        function = entry.function
        self.run, self.entry, self.function = run, entry, function
        self.n_in, self.n_out = function.n_in(), function.n_out()
        self.sizes_in = [function.nnz_in(k) for k in range(self.n_in)]
        self.sizes_out = [function.nnz_out(k) for k in range(self.n_out)]
        offsets = np.cumsum([0, *self.sizes_out]).tolist()
        self.spans = list(zip(offsets[:-1], offsets[1:], strict=True))  # in one array a row
        self.total = offsets[-1]
        # the fixed inputs (a bound function's d) read at the same address by every row; the
        # caller gives the others
        self.given = [k for k in range(self.n_in) if k not in entry.fixed]
        self.in_p = (ctypes.c_void_p * max(self.n_in, 1))()
        for k, values in entry.fixed.items():
            self.in_p[k] = values.ctypes.data
        self.out_p = (ctypes.c_void_p * max(self.n_out, 1))()
        self.in_stride = np.zeros(max(self.n_in, 1), np.int64)
        self.out_stride = np.array(self.sizes_out or [0], np.int64)
        self.struct = ctypes.byref(entry.struct)
        self.tail = (self.n_in, ctypes.addressof(self.in_p), self.in_stride.ctypes.data,
                     self.n_out, ctypes.addressof(self.out_p), self.out_stride.ctypes.data)

    def __call__(self, rows: int, *inputs) -> tuple[np.ndarray, ...]:
        if len(inputs) != len(self.given):
            raise TypeError(f"{self.function.name()} takes {len(self.given)} inputs, "
                            f"{len(inputs)} given")
        kept = []  # the arrays the pointers point into, alive through the call
        for k, given in zip(self.given, inputs, strict=True):
            size = self.sizes_in[k]
            if given is None or not size:
                self.in_p[k] = None
                continue
            a = np.ascontiguousarray(given, float)
            if a.shape == (rows, size) or (size == 1 and a.shape == (rows,)):
                self.in_stride[k] = size
            elif a.shape == (size,):
                self.in_stride[k] = 0
            else:
                raise ValueError(f"{self.function.name()}'s input {k} has shape {a.shape}, "
                                 f"not ({rows}, {size}) or ({size},)")
            kept.append(a)
            self.in_p[k] = a.ctypes.data
        out = np.empty(rows * self.total)
        base = out.ctypes.data
        for k, (start, _) in enumerate(self.spans):
            self.out_p[k] = base + 8 * rows * start
        failed = self.run(self.struct, rows, *self.tail)
        if failed:
            raise RuntimeError(f"{self.function.name()} failed to evaluate at row {failed - 1}")
        return tuple(out[rows * a:rows * b].reshape(rows, b - a) for a, b in self.spans)


def rows_call(function: ca.Function) -> RowsCall | None:
    """A RowsCall of `function` where it has a C entry point (casmech loaded it from a
    library, or bound such a function to the model data: backends.external_record), its
    inputs and outputs are dense and the loop's library is there; else None."""
    found = rk_library.unbound(function)
    if found is None:
        return None
    function, fixed = found
    path = external_record.library(function)
    if path is None or not all(function.sparsity_in(k).is_dense()
                               for k in range(function.n_in())) or not all(
            function.sparsity_out(k).is_dense() for k in range(function.n_out())):
        return None
    run = rk_library.rows_driver()
    if run is None:
        return None
    try:
        return RowsCall(run, rk_library.Entry(function, path, fixed))
    except (AttributeError, OSError, ValueError):
        return None
