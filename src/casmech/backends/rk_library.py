"""The explicit Runge-Kutta driver of c/casmech_rk.c and the loop over rows of
c/casmech_rows.c as shared libraries, each built once per machine through the compiled-model
cache (keyed by its C source, the compiler and its flags) and loaded by ctypes, and the C entry
points of a compiled CasADi function for them to call.

A function casmech loaded from a library (backends.load: a casadi.external) is reached at its
own symbol in its own file, which backends.external_record recorded when it was loaded (ctypes
opens the same file: the dynamic loader hands back the handle CasADi holds). A function bound to
the model data (backends.parametric.bind: the external called with its last input d a
constant, recorded as such) is reached through that external, d passed as its last input. Any
other function (SX, other MX, an external casmech did not load) has no C entry point here:
`entry` returns None and the caller integrates in Python.
"""

from __future__ import annotations

import ctypes
import hashlib
import json
import weakref
from pathlib import Path

import casadi as ca
import numpy as np

from casmech.backends import external_record
from casmech.backends.build import SUFFIX

LIBRARY = "libcasmech_rk" + SUFFIX
SOURCE = Path(__file__).resolve().parent / "c" / "casmech_rk.c"
ROWS_LIBRARY = "libcasmech_rows" + SUFFIX
ROWS_SOURCE = SOURCE.with_name("casmech_rows.c")
FLAGS = ("-O2",)  # a small fixed file: its loops gain from -O2, its build stays short
# casmech_rk.c's return codes and counters
DONE, TOO_SMALL, MAX_STEPS, EVAL_FAILED, NOT_FINITE = range(5)
ACCEPTED, REJECTED, EVALUATIONS, OUTPUTS, PROJECTIONS, HERMITE, COUNT = range(7)

_int = ctypes.c_longlong  # casadi_int of CasADi's generated C (backends.generate)
_double_p = ctypes.POINTER(ctypes.c_double)


class Function(ctypes.Structure):
    _fields_ = [("eval", ctypes.c_void_p), ("arg", ctypes.POINTER(_double_p)),
                ("res", ctypes.POINTER(_double_p)), ("iw", ctypes.POINTER(_int)),
                ("w", _double_p), ("mem", ctypes.c_int), ("i_t", ctypes.c_int),
                ("i_x", ctypes.c_int), ("i_out", ctypes.c_int)]


class Tableau(ctypes.Structure):
    _fields_ = [("n_stages", ctypes.c_int), ("n_extended", ctypes.c_int),
                ("n_dense", ctypes.c_int), ("a", _double_p), ("b", _double_p),
                ("c", _double_p), ("e3", _double_p), ("e5", _double_p), ("d", _double_p),
                ("error_order", ctypes.c_double)]


class Settings(ctypes.Structure):
    _fields_ = [("rtol", ctypes.c_double), ("atol", ctypes.c_double),
                ("max_step", ctypes.c_double), ("first_step", ctypes.c_double),
                ("safety", ctypes.c_double), ("min_factor", ctypes.c_double),
                ("max_factor", ctypes.c_double), ("max_steps", _int),
                ("hermite_below", ctypes.c_double)]


def pointer(array: np.ndarray):
    """A double* to a C-contiguous float64 array (kept alive by its caller)."""
    return array.ctypes.data_as(_double_p)


_loaded: dict = {}


def driver():
    """casmech_rk_run from the cached library (built on a miss), or None without a C compiler
    or when the build failed."""
    if "run" not in _loaded:
        _loaded["run"] = _load("rk driver", SOURCE, LIBRARY, "casmech_rk_run", ctypes.c_int, [
            ctypes.POINTER(Tableau), ctypes.POINTER(Settings), ctypes.POINTER(Function),
            ctypes.POINTER(Function), ctypes.c_int, ctypes.c_double, _double_p, ctypes.c_int,
            _double_p, _double_p, _double_p, ctypes.POINTER(_int), _double_p])
    return _loaded["run"]


def rows_driver():
    """casmech_rows_run (c/casmech_rows.c: a function, or a chain of its parts, over rows in C
    loops) from the cached library (built on a miss), or None without a C compiler or when
    the build failed."""
    if "rows" not in _loaded:
        _loaded["rows"] = _load("rows driver", ROWS_SOURCE, ROWS_LIBRARY, "casmech_rows_run",
                                _int, [ctypes.c_int, ctypes.c_void_p, _int, ctypes.c_int,
                                       ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                                       ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p,
                                       ctypes.c_void_p])
    return _loaded["rows"]


def _load(kind: str, path: Path, name: str, symbol: str, restype, argtypes):
    from casmech.backends import build, cache
    from casmech.errors import AnalysisError, UsageError

    toolchain = build.Toolchain(flags=FLAGS)
    if not build.available(toolchain):
        return None
    source = path.read_bytes()
    key = hashlib.sha256(json.dumps({
        "kind": kind, "source": hashlib.sha256(source).hexdigest(),
        "compiler": toolchain.version(), "flags": list(toolchain.all_flags)},
        sort_keys=True).encode()).hexdigest()[:32]
    try:
        directory, _ = cache.lookup(
            key, lambda d: _build(d, kind, path.name, source, name, symbol, toolchain))
    except (AnalysisError, UsageError, OSError):
        return None
    function = getattr(ctypes.CDLL(str(directory / name)), symbol)
    function.restype, function.argtypes = restype, argtypes
    return function


def _build(directory: Path, kind: str, file: str, source: bytes, name: str, symbol: str,
           toolchain) -> None:
    """The library and a manifest naming it with its sha256 (what codegen.trust checks)."""
    from casmech.backends import build, manifest

    (directory / file).write_bytes(source)
    build.build_libraries({name: [directory / file]}, directory, toolchain)
    (directory / manifest.MANIFEST).write_text(json.dumps({
        "format": manifest.FORMAT, "model": kind, "library": name,
        "functions": [{"name": symbol, "library": name}],
        manifest.DIGESTS: {name: manifest.sha256(directory / name)}}, indent=1))


class Entry:
    """A compiled function's C entry point and work vectors as casmech_rk.c's cm_function:
    its input `t` and `x` (-1 where it has none: the rows' loop reads neither) and its first
    output, its other inputs `fixed` (position ->
    dense values, held here; the rest NULL: zeros); the casadi Function kept alive with it (its
    library stays loaded), its memory checked out and released with this object."""

    def __init__(self, function: ca.Function, path: Path, fixed: dict | None = None):
        self.function = function
        name = function.name()
        library = ctypes.CDLL(str(path))
        symbol = getattr(library, name)
        names = function.name_in()
        self.arg = (_double_p * max(function.sz_arg(), function.n_in()))()
        self.res = (_double_p * max(function.sz_res(), function.n_out()))()
        self.fixed = {i: np.ascontiguousarray(v, float) for i, v in (fixed or {}).items()}
        for i, values in self.fixed.items():
            self.arg[i] = pointer(values)
        self.iw = np.zeros(max(function.sz_iw(), 1), np.int64)
        self.w = np.zeros(max(function.sz_w(), 1))
        mem = 0
        checkout = getattr(library, f"{name}_checkout", None)
        if checkout is not None:
            checkout.restype = ctypes.c_int
            mem = checkout()
            release = getattr(library, f"{name}_release")
            release.argtypes = [ctypes.c_int]
            weakref.finalize(self, release, mem)
        self.struct = Function(
            ctypes.cast(symbol, ctypes.c_void_p).value, self.arg, self.res,
            self.iw.ctypes.data_as(ctypes.POINTER(_int)), pointer(self.w), mem,
            names.index("t") if "t" in names else -1,
            names.index("x") if "x" in names else -1, 0)


def unbound(function: ca.Function) -> tuple[ca.Function, dict] | None:
    """(the function casmech loaded, {its last input: d}) of a function bound to the model data
    d (backends.external_record), (function, {}) of any other; None where d does not fill that
    input densely."""
    found = external_record.binding(function)
    if found is None:
        return function, {}
    function, d = found
    last = function.n_in() - 1
    if not function.sparsity_in(last).is_dense() or function.nnz_in(last) != d.size:
        return None
    return function, {last: d}


def entry(function: ca.Function) -> Entry | None:
    """`function`'s C entry point (Entry) when casmech loaded it from a library, or bound such
    a function to the model data (backends.external_record), and its inputs besides t, x (and
    the bound d) are empty (NULL reads as zeros) and its first output is the derivative; else
    None."""
    found = unbound(function)
    if found is None:
        return None
    function, fixed = found
    path = external_record.library(function)
    names = function.name_in()
    if path is None or "x" not in names or any(
            function.nnz_in(i) for i, name in enumerate(names)
            if name not in ("t", "x") and i not in fixed):
        return None
    if function.nnz_out(0) != function.nnz_in(names.index("x")) or not (
            function.sparsity_in("x").is_dense() and function.sparsity_out(0).is_dense()):
        return None
    try:
        return Entry(function, path, fixed)
    except (AttributeError, OSError):
        return None
