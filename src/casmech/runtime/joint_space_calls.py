"""The NumPy calls of a joint space (formulations.joint_space.JointSpace.calls) through buffers
(runtime.buffers.BufferedCall): arrays copied into and out of a Function's buffer instead of
converted to and from CasADi's DM, each function's call made on its first use, over the
function with its outputs dense (a buffer takes dense outputs; a derivative's structural zeros
are written as zeros). A space's calls run one at a time (a buffer is one), so the space may be
shared by threads."""

from __future__ import annotations

import threading
from collections.abc import Iterator, Mapping

import casadi as ca

from casmech.runtime.buffers import BufferedCall


class Calls(Mapping):
    """name -> a thread-safe NumPy call of functions[name] (module docstring)."""

    def __init__(self, functions: Mapping[str, ca.Function]):
        self._functions, self._calls = functions, {}
        self._lock = threading.Lock()

    def __getitem__(self, name: str):
        call = self._calls.get(name)
        if call is None:
            with self._lock:
                call = self._calls.get(name) or _Locked(
                    BufferedCall(_dense(self._functions[name]), stoppable=False), self._lock)
                self._calls[name] = call
        return call

    def __iter__(self) -> Iterator[str]:
        return iter(self._functions)

    def __len__(self) -> int:
        return len(self._functions)


class _Locked:
    def __init__(self, call: BufferedCall, lock: threading.Lock):
        self.call, self.lock = call, lock

    def __call__(self, *arrays) -> tuple:
        with self.lock:
            return self.call(*arrays)


def _dense(function: ca.Function) -> ca.Function:
    """`function` with every output dense, under its name and its inputs' and outputs' names."""
    if all(function.sparsity_out(k).is_dense() for k in range(function.n_out())):
        return function
    inputs = function.sx_in() if function.is_a("SXFunction") else function.mx_in()
    return ca.Function(function.name(), inputs,
                       [ca.densify(out) for out in function.call(inputs)],
                       function.name_in(), function.name_out())
