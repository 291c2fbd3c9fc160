"""The NumPy calls of a joint space (formulations.joint_space.JointSpace.calls) through each
function's buffer: its inputs and outputs bound once to NumPy arrays (casadi's
Function.buffer), the arguments copied into its inputs, the outputs copied out as fresh
arrays, instead of CasADi's conversions to and from DM; a trailing input the space fixes (a
compiled space's model data) is written once. Each function's call is made on its first use,
over the function with its outputs dense (a derivative's structural zeros are written as
zeros). A call holds its buffers' lock while it writes, evaluates and copies out, so the space
may be shared by threads.

A call's Python costs more than the C of a small robot's forward dynamics, so each function's
call is one function compiled from a text made for its inputs and outputs, with no loop: each
vector argument copied by a memoryview's slice assignment (which takes only an array of float64
of the input's shape: nothing is spread or converted), the time "t" as one element. Anything
else (a number, a list, a column, integers, a wrong size) takes the general path, which copies
any argument whose numbers fill the input, whatever its shape, and raises a ValueError naming
the function, the input and the sizes for the rest (a number or a one-element array is not
spread over a longer input)."""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping

import casadi as ca
import numpy as np

from casmech.formulations.joint_space import VECTORS
from casmech.numerics.dense_outputs import dense_outputs

TIME = "t"  # the input written as one number (SIGNATURES' time)


class Calls(dict):
    """name -> a thread-safe NumPy call of functions[name] (module docstring): the call takes
    the function's inputs but the trailing ones `trailing` gives and returns its outputs as
    fresh arrays, those named in VECTORS 1-D and the others 2-D: the array of a function of one
    output, else a tuple of them. `trailing(name)`: the values of the inputs functions[name]
    takes after the space's (a compiled joint space's "d", asked for once the function is at
    hand: backends.joint_space_library); None: no such inputs. A dict whose values are, until
    first called, stand-ins that make the call and put it in their place."""

    def __init__(self, functions: Mapping[str, ca.Function],
                 trailing: Callable[[str], tuple] | None = None):
        super().__init__((name, _Unmade(self, name)) for name in functions)
        self._functions, self._trailing = functions, trailing
        self._lock = threading.Lock()

    def _make(self, name: str) -> Callable:
        """The call of `name`, made once (under the lock) and put in the stand-in's place."""
        with self._lock:
            call = self[name]
            if isinstance(call, _Unmade):
                function = dense_outputs(self._functions[name])
                call = _call(function, () if self._trailing is None else self._trailing(name))
                self[name] = call
        return call


class _Unmade:
    """Calls' stand-in for the call of `name` before its first use."""

    def __init__(self, calls: Calls, name: str):
        self.calls, self.name = calls, name

    def __call__(self, *arrays):
        return self.calls._make(self.name)(*arrays)


# the call of a function of inputs x0, x1, ... (the trailing fixed ones left out); {copies}:
# each input copied into its buffer
_TEXT = """\
def {name}({arguments}):
    acquire()
    try:
        try:
            {copies}
        except (TypeError, ValueError):
            write({packed})
        evaluate()
        return {outputs}
    finally:
        release()
"""


def _call(function: ca.Function, trailing: tuple) -> Callable:
    """function(*arrays) -> its outputs as Calls gives them, through the function's buffer
    (module docstring); `trailing` the values of its last inputs, written once."""
    buffer, evaluate = function.buffer()
    # casadi stores a matrix column by column: each array is its matrix's transpose, a
    # vector's its numbers (the buffer holds their addresses: the call's scope keeps them)
    inputs = [np.zeros(function.size_in(i)[::-1]) for i in range(function.n_in())]
    outputs = [np.empty(function.numel_out(i)) if name in VECTORS else
               np.empty(function.size_out(i)[::-1])
               for i, name in enumerate(function.name_out())]
    for i, array in enumerate(inputs):
        buffer.set_arg(i, memoryview(array.reshape(-1)))
    for i, array in enumerate(outputs):
        buffer.set_res(i, memoryview(array.reshape(-1)))
    given = len(inputs) - len(trailing)
    for array, value in zip(inputs[given:], trailing, strict=True):
        array.reshape(-1)[:] = np.ravel(value)
    flat = [array.reshape(-1) for array in inputs[:given]]  # views of the inputs
    names = function.name_in()[:given]
    lock = threading.Lock()
    scalar = [name == TIME and f.size == 1 for name, f in zip(names, flat, strict=True)]

    def write(arrays: tuple) -> None:
        """The general path: each argument's numbers in order whatever its shape, its size
        the input's."""
        for k, (target, array) in enumerate(zip(flat, arrays, strict=True)):
            try:
                values = np.ravel(array)
                if values.size != target.size:
                    raise ValueError
                target[:] = values
            except (ValueError, TypeError):
                raise ValueError(f"{function.name()}: {names[k]} takes {target.size} "
                                 f"number{'s' * (target.size != 1)}, got "
                                 f"{np.shape(array) or repr(array)}") from None

    arguments = "".join(f"x{k}, " for k in range(given))
    copies = "; ".join(f"f{k}[0] = x{k}" if scalar[k] else f"m{k}[:] = x{k}"
                       for k in range(given)) or "pass"
    copied = "".join(f"o{k}.copy(), " for k in range(len(outputs)))
    scope = {"acquire": lock.acquire, "release": lock.release, "evaluate": evaluate,
             "write": write, "buffer": buffer, "inputs": inputs,
             **{f"f{k}": f for k, f in enumerate(flat)},
             **{f"m{k}": memoryview(f) for k, f in enumerate(flat)},
             **{f"o{k}": o.T for k, o in enumerate(outputs)}}  # (a matrix's view)
    # (named as the function where that name is free: Python's message for a wrong number of
    # arguments names it)
    name = function.name() if function.name().isidentifier() and \
        function.name() not in scope else "call"
    text = _TEXT.format(name=name, arguments=arguments, copies=copies, packed=f"({arguments})",
                        outputs=copied[:-2] if len(outputs) == 1 else f"({copied})")
    exec(text, scope)  # noqa: S102 (made of indices and an identifier)
    return scope[name]
