"""Calls of casadi Functions with NumPy arrays in and out, through Function.buffer: inputs are
read from and outputs written into NumPy memory, without the element-by-element conversion of
a returned DM (np.array(DM) costs more than evaluating a mapped prescribed step over 10^5 rows).
Functions with a sparse input or output are called the ordinary way."""

from __future__ import annotations

import casadi as ca
import numpy as np


class BufferedCall:
    """function(*arrays) -> tuple of dense NumPy arrays, one per output."""

    def __init__(self, function: ca.Function):
        self.function = function
        n_in, n_out = function.n_in(), function.n_out()
        self.dense = all(function.sparsity_in(i).is_dense() for i in range(n_in)) and \
            all(function.sparsity_out(i).is_dense() for i in range(n_out))
        self.shapes_in = [function.size_in(i) for i in range(n_in)]
        self.shapes_out = [function.size_out(i) for i in range(n_out)]
        if self.dense:
            self.buffer, self.evaluate = function.buffer()

    def __call__(self, *args) -> tuple[np.ndarray, ...]:
        if not self.dense:
            outputs = self.function(*args)
            outputs = outputs if isinstance(outputs, tuple) else (outputs,)
            return tuple(np.array(o, float) for o in outputs)
        # casadi stores a dense matrix column by column: the C-ordered transpose
        inputs = [np.ascontiguousarray(np.asarray(a, float).reshape(shape).T)
                  for a, shape in zip(args, self.shapes_in, strict=True)]
        outputs = [np.empty(shape[::-1]) for shape in self.shapes_out]
        for i, a in enumerate(inputs):
            self.buffer.set_arg(i, memoryview(a.reshape(-1)))
        for i, out in enumerate(outputs):
            self.buffer.set_res(i, memoryview(out.reshape(-1)))
        self.evaluate()
        return tuple(out.T for out in outputs)
