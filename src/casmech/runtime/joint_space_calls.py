"""The NumPy calls of a joint space (formulations.joint_space.JointSpace.calls) through each
function's buffer: its inputs and outputs bound once to NumPy arrays (casadi's
Function.buffer), an argument copied into its input, the outputs copied out, instead of
CasADi's conversions to and from DM; a trailing input the space fixes (a compiled space's model
data) is written once. Each function's call is made on its first use, over the function with
its outputs dense (a derivative's structural zeros are written as zeros). A space's calls run
one at a time (the buffers are the space's), so the space may be shared by threads."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator, Mapping

import casadi as ca
import numpy as np

from casmech.numerics.dense_outputs import dense_outputs


class Calls(Mapping):
    """name -> a thread-safe NumPy call of functions[name] (module docstring); `data`: what
    gives the value of the trailing input every function takes besides the space's (a compiled
    joint space's "d", asked for once a function is at hand: backends.joint_space_library),
    None: no such input."""

    def __init__(self, functions: Mapping[str, ca.Function],
                 data: Callable[[], np.ndarray] | None = None):
        self._functions, self._calls, self._data = functions, {}, data
        self._lock = threading.Lock()

    def __getitem__(self, name: str):
        call = self._calls.get(name)
        if call is None:
            with self._lock:
                call = self._calls.get(name)
                if call is None:
                    function = dense_outputs(self._functions[name])
                    call = _Call(function, () if self._data is None else (self._data(),),
                                 self._lock)
                self._calls[name] = call
        return call

    def __iter__(self) -> Iterator[str]:
        return iter(self._functions)

    def __len__(self) -> int:
        return len(self._functions)


class _Call:
    """function(*arrays) -> a tuple of fresh 2-D arrays, one per output, through the function's
    buffer; `trailing` the values of its last inputs, written once; calls under `lock`."""

    def __init__(self, function: ca.Function, trailing: tuple, lock: threading.Lock):
        self.name, self.lock = function.name(), lock
        self.buffer, self.evaluate = function.buffer()
        # casadi stores a matrix column by column: each array is its matrix's transpose
        # (kept here: the buffer holds their addresses, not the arrays)
        self.inputs = inputs = [np.zeros(function.size_in(i)[::-1])
                                for i in range(function.n_in())]
        self.outputs = [np.empty(function.size_out(i)[::-1]) for i in range(function.n_out())]
        for i, array in enumerate(inputs):
            self.buffer.set_arg(i, memoryview(array.reshape(-1)))
        for i, array in enumerate(self.outputs):
            self.buffer.set_res(i, memoryview(array.reshape(-1)))
        given = len(inputs) - len(trailing)
        for array, value in zip(inputs[given:], trailing, strict=True):
            array.reshape(-1)[:] = np.ravel(value)
        self.flat = [array.reshape(-1) for array in inputs[:given]]  # views of the inputs
        self.names = function.name_in()[:given]

    def __call__(self, *arrays) -> tuple:
        if len(arrays) != len(self.flat):
            raise TypeError(f"{self.name} takes {len(self.flat)} arguments, {len(arrays)} given")
        with self.lock:
            for k, (flat, array) in enumerate(zip(self.flat, arrays, strict=True)):
                try:
                    flat[:] = array if np.ndim(array) <= 1 else np.ravel(array)
                except (ValueError, TypeError):
                    raise ValueError(f"{self.name}: {self.names[k]} takes {flat.size} "
                                     f"number{'s' * (flat.size != 1)}, got "
                                     f"{np.shape(array) or repr(array)}") from None
            self.evaluate()
            return tuple(out.T.copy() for out in self.outputs)
