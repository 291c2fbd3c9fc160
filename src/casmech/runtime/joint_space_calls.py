"""The NumPy calls of a joint space (formulations.joint_space.JointSpace.calls) through buffers
(runtime.buffers.BufferedCall): arrays copied into and out of a Function's buffer instead of
converted to and from CasADi's DM, each function's call made on its first use, over the
function with its outputs dense (a buffer takes dense outputs; a derivative's structural zeros
are written as zeros). A space's calls run one at a time (a buffer is one), so the space may be
shared by threads."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator, Mapping

import casadi as ca
import numpy as np

from casmech.numerics.dense_outputs import dense_outputs
from casmech.runtime.buffers import BufferedCall


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
                    call = _Locked(BufferedCall(function, stoppable=False), self._lock,
                                   () if self._data is None else (self._data(),))
                self._calls[name] = call
        return call

    def __iter__(self) -> Iterator[str]:
        return iter(self._functions)

    def __len__(self) -> int:
        return len(self._functions)


class _Locked:
    def __init__(self, call: BufferedCall, lock: threading.Lock, trailing: tuple):
        self.call, self.lock, self.trailing = call, lock, trailing

    def __call__(self, *arrays) -> tuple:
        with self.lock:
            return self.call(*arrays, *self.trailing)
