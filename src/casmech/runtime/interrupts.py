"""Stopping an analysis on SIGINT or SIGTERM, promptly, keeping the rows computed so far.

`trap()` (used by `casmech run`) installs a handler for both signals. The first signal makes an
`errors.Interrupted` pending, an AnalysisError, so the analyses attach the rows they have
computed (`partial`) exactly as they do for a failure; the caller writes them and exits 128 +
the signal's number. It is raised at a safe point:

- inside an integrator (IDAS, CVODES): at once, which stops the solver; CasADi turns it into a
  RuntimeError, and the code that catches CasADi's RuntimeError there calls `check()` first,
  so an interrupt is never taken for a solver failure (and retried). Only code inside a
  `solver()` block (the integrator calls of runtime.dynamics and runtime.joint_dynamics, which
  catch that RuntimeError) is such a place, and only while CasADi's Function.call runs: a
  raise elsewhere inside CasADi's Python wrappers would come out as a garbled
  NotImplementedError;
- otherwise at the next row (`watch` wraps the row callback of casmech.analyze) or at the next
  `check()` of the caller (after loading, after compiling).

A second signal says it is stopping; a third ends the process at once (exit 128 + signal, the
rows not written; metadata.json still says "running"). While results are written (`saving()`)
signals wait.

Outside `trap()` (the Python API), Ctrl-C raises KeyboardInterrupt as usual; `check()` turns
the RuntimeError CasADi makes of it back into an `Interrupted`, which is a KeyboardInterrupt.
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from casmech.errors import Interrupted

SIGNALS = (signal.SIGINT, signal.SIGTERM)
ABANDON = 3  # the signal that ends the process without writing

_pending: Interrupted | None = None
_count = 0
_saving = 0
_solvers = 0  # solver() blocks entered and not left
_casadi_call = None  # code object of casadi.Function.call


def pending() -> Interrupted | None:
    return _pending


def check(error: BaseException | None = None) -> None:
    """Raise the pending interrupt, if any; or an Interrupted for a RuntimeError CasADi made of
    a KeyboardInterrupt (`error`)."""
    if _pending is not None:
        raise _pending
    if error is not None and "KeyboardInterrupt" in str(error):
        raise Interrupted(signal.SIGINT) from None


def watch(callback: Callable[[float], None] | None) -> Callable[[float], None]:
    """A row callback (casmech.analyze's `progress`) that raises a pending interrupt."""
    def on_row(t: float) -> None:
        check()
        if callback is not None:
            callback(t)

    return on_row


def _in_solver(frame) -> bool:
    """Whether the signal came while CasADi's Function.call ran inside a solver() block."""
    return _solvers > 0 and frame is not None and frame.f_code is _casadi_call


def _handler(signum: int, frame) -> None:
    global _pending, _count
    _count += 1
    name = signal.Signals(signum).name
    if _count >= ABANDON:
        print(f"casmech: {name} again: stopped without writing the rows", file=sys.stderr)
        os._exit(128 + signum)
    if _pending is None:
        _pending = Interrupted(signum)
    elif not _saving:
        print(f"casmech: stopping at the next row ({name} once more ends at once, without "
              "writing the rows)", file=sys.stderr)
    if not _saving and _in_solver(frame):
        raise _pending


def _register() -> None:
    global _casadi_call
    import casadi

    _casadi_call = casadi.Function.call.__code__


@contextmanager
def trap() -> Iterator[None]:
    """SIGINT and SIGTERM raise Interrupted within this block (restored after it)."""
    global _pending, _count
    _register()
    previous = {number: signal.signal(number, _handler) for number in SIGNALS}
    _pending, _count = None, 0
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
        _pending, _count = None, 0


@contextmanager
def saving() -> Iterator[None]:
    """Within this block a signal does not interrupt (the rows are being written)."""
    global _saving
    _saving += 1
    try:
        yield
    finally:
        _saving -= 1


@contextmanager
def solver() -> Iterator[None]:
    """Within this block a signal stops CasADi's integrator at once: the code inside catches
    the RuntimeError CasADi makes of it and calls check() before treating it as a failure."""
    global _solvers
    _solvers += 1
    try:
        yield
    finally:
        _solvers -= 1
