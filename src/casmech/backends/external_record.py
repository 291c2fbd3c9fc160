"""What casmech knows of the functions it makes from compiled libraries, recorded where it
makes them: the library file each casadi.external was loaded from (backends.load), and for a
function bound to the model data (backends.parametric.bind: the function called with its
last input d a constant) the function it calls and d. backends.rk_library reads it to reach a
function's C entry point; a function casmech did not make this way has no entry.

An entry is keyed by the function's CasADi object (`Function.__hash__()`: the address of the
shared C++ object, the same for every Python wrapper of one function, distinct between live
functions) and lasts as long as the wrapper casmech handed out: the entry holds a wrapper of
its own, so while it exists its object lives and its key names no other function, and a
finalizer of the handed-out wrapper removes it (its object may then be freed and its address
reused). A function reached only through another wrapper after that one is gone has no
entry.
"""

from __future__ import annotations

import weakref
from pathlib import Path

import casadi as ca
import numpy as np

from casmech.core.records import record


@record(eq=False)
class Loaded:
    """A casadi.external and the library file it was loaded from."""

    function: ca.Function
    path: Path


@record(eq=False)
class Bound:
    """A function that calls `inner` with `d` as its last input, its other inputs its own."""

    function: ca.Function
    inner: ca.Function
    d: np.ndarray


_ENTRIES: dict[int, Loaded | Bound] = {}


def loaded(function: ca.Function, path: Path) -> ca.Function:
    """`function` (a casadi.external), recorded as loaded from `path`."""
    return _recorded(function, Loaded(ca.Function(function), Path(path)))


def bound(function: ca.Function, inner: ca.Function, d) -> ca.Function:
    """`function`, recorded as `inner` called with d (a dense vector) as its last input."""
    values = np.array(d, float).ravel()
    values.setflags(write=False)
    return _recorded(function, Bound(ca.Function(function), inner, values))


def library(function: ca.Function) -> Path | None:
    """The library file of a recorded external, or None."""
    entry = _ENTRIES.get(function.__hash__())
    return entry.path if isinstance(entry, Loaded) else None


def binding(function: ca.Function) -> tuple[ca.Function, np.ndarray] | None:
    """(the function it calls, d) for a recorded bound function, or None."""
    entry = _ENTRIES.get(function.__hash__())
    return (entry.inner, entry.d) if isinstance(entry, Bound) else None


def _recorded(function: ca.Function, entry: Loaded | Bound) -> ca.Function:
    key = function.__hash__()
    _ENTRIES[key] = entry
    finalizer = weakref.finalize(function, _forget, key, entry)
    finalizer.atexit = False
    return function


def _forget(key: int, entry: Loaded | Bound) -> None:
    if _ENTRIES.get(key) is entry:  # not one recorded since for the same object
        del _ENTRIES[key]
