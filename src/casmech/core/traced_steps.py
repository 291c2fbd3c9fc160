"""Per-body steps of the joint formulation's recursions as small SX Functions: a step is
traced once per structure of its arguments (shapes and sparsity patterns, and the `static`
values it branches on) and then evaluated on each body's arguments inside CasADi.

One evaluation replaces the step's tens to hundreds of Python-level SX operations, whose
wrappers (argument conversion, shape checks) cost far more than the SX nodes they make: the
unrolled recursions of a large tree spent most of their build there
(docs/decisions/traced-steps.md). Evaluating an SX Function on SX arguments
expands it (no call node), and CasADi's SX arithmetic folds operations on constants and drops
x * 0, x + 0 and x * 1, so the expanded graph is the one the step's code builds when run on the
arguments directly, up to the association of products of constants. `direct()` runs every step
on its arguments instead (the tests compare both).
"""

from __future__ import annotations

from collections.abc import Callable
from contextlib import contextmanager

import casadi as ca
import numpy as np

_DIRECT = [False]  # run steps on their arguments (no tracing): see direct()


class Traced:
    """A step `fn(*matrices, **static) -> tuple of matrices`, traced per argument structure.
    `fn` must not look at its matrix arguments' values (only at `static`, part of the key)."""

    def __init__(self, fn: Callable):
        self.fn = fn
        self.functions: dict[tuple, ca.Function] = {}

    def __call__(self, *args, **static) -> list:
        if _DIRECT[0]:
            return list(self.fn(*args, **static))
        args = [a if isinstance(a, (ca.SX, ca.DM)) else _as_sx(a) for a in args]
        key = (tuple(sorted(static.items())), *(_structure(a) for a in args))
        function = self.functions.get(key)
        if function is None:
            symbols = [ca.SX.sym(f"a{k}", a.sparsity()) for k, a in enumerate(args)]
            outputs = list(self.fn(*symbols, **static))
            function = ca.Function("step_" + self.fn.__name__.strip("_"), symbols, outputs)
            self.functions[key] = function
        return function.call(args)


def traced(fn: Callable) -> Traced:
    return Traced(fn)


@contextmanager
def direct():
    """Within: every Traced step runs its code on its arguments (the graphs before tracing)."""
    _DIRECT[0] = True
    try:
        yield
    finally:
        _DIRECT[0] = False


def _as_sx(value) -> ca.SX:
    """A constant argument other than a DM (a number, a NumPy array) as SX. A DM is passed as
    it is: the call converts it in CasADi, structural zeros kept, as SX(DM) would."""
    return ca.SX(ca.DM(np.asarray(value, float)))


def _structure(matrix: ca.SX | ca.DM) -> tuple:
    if matrix.is_dense():
        return matrix.size()
    sparsity = matrix.sparsity()
    return matrix.size(), tuple(sparsity.colind()), tuple(sparsity.row())
