"""A function evaluated over many states, one row each: in one C loop over the rows where
casmech loaded the function from a library (backends.rows_loop), else by casadi's map over
columns (runtime.buffers.ColumnCall)."""

from __future__ import annotations

import sys

import casadi as ca
import numpy as np

from casmech.runtime.buffers import ColumnCall


def over_rows(function: ca.Function):
    """`function` over many states, for rows_of(): in one C loop over the rows where a library
    casmech loaded holds it (backends.rows_loop.RowsCall; backends is imported only once a
    library was loaded, as its functions are recorded then), else by casadi's map over
    columns (ColumnCall)."""
    if sys.modules.get("casmech.backends.external_record") is not None:
        from casmech.backends.rows_loop import rows_call

        call = rows_call(function)
        if call is not None:
            return call
    return ColumnCall(function)


def rows_of(call, times: np.ndarray, *inputs: np.ndarray) -> tuple[np.ndarray, ...]:
    """An over_rows call at each of `times`: each input one row per time (len(times) x n) or
    a vector every evaluation shares; each output one row per time (the rows' C loop's own
    layout; casadi's map's columns transposed)."""
    if type(call) is ColumnCall:
        return tuple(out.T for out in call(times[None, :], *(
            a.T if a.ndim == 2 else a[:, None] for a in inputs)))
    return call(len(times), times, *inputs)
