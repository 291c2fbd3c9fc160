"""SIGINT and SIGTERM stop an analysis promptly, keeping the rows computed so far.

`trap()` (used by `casmech run` and `casmech sweep`) installs a handler for both signals that
cancels the run's runtime.cancel.CancelToken: the analysis raises errors.Interrupted (with the
rows computed so far in `partial`) at its next poll, between solver calls and blocks of rows,
or at once inside an integrator's evaluation (runtime.cancel.solving: the handler raises there,
which stops IDAS or CVODES within one residual evaluation). The caller writes the rows and
exits 128 + the signal's number. A run that had computed every row when the signal came is
complete.

A second signal says it is stopping; a third ends the process at once (exit 128 + signal, the
rows not written; metadata.json still says "running"). While results are written (`saving()`)
a signal waits.

Outside `trap()` (the Python API), casmech.analyze handles Ctrl-C the same way for the
duration of a run in the main thread (`guard`), so the Interrupted it raises, a
KeyboardInterrupt, carries the rows.
"""

from __future__ import annotations

import _signal
import os
import signal
import sys
from collections.abc import Iterator
from contextlib import contextmanager

from casmech.runtime import cancel
from casmech.runtime.cancel import CancelToken

SIGNALS = (signal.SIGINT, signal.SIGTERM)
ABANDON = 3  # the signal that ends the process without writing
_SIGINT = int(signal.SIGINT)


class _Trap:
    """The token signals cancel, how many came, whether results are being written, whether a
    third signal ends the process (the command line's, not a Python caller's)."""

    def __init__(self, token: CancelToken, abandon: bool = True):
        self.token, self.count, self.saving, self.abandon = token, 0, 0, abandon

    def handler(self, signum: int, frame) -> None:
        self.count += 1
        name = signal.Signals(signum).name
        if self.abandon and self.count >= ABANDON:
            print(f"casmech: {name} again: stopped without writing the rows", file=sys.stderr)
            os._exit(128 + signum)
        if self.token.cancelled and not self.saving and self.abandon:
            print(f"casmech: stopping at the next row ({name} once more ends at once, without "
                  "writing the rows)", file=sys.stderr)
        running = cancel.current() or self.token  # a caller's own token, if it gave one
        for token in {id(self.token): self.token, id(running): running}.values():
            token.cancel(signum)
        if not self.saving and cancel.armed():
            running.check()  # inside a solver call: stops it


_traps: list[_Trap] = []  # trap() blocks entered and not left, innermost last


def pending() -> int | None:
    """The signal that came within the innermost trap(), if any."""
    return _traps[-1].token.signum if _traps else None


def check(error: BaseException | None = None) -> None:
    """Raise Interrupted if a signal came (the innermost trap's token, else the running
    run's); or for a RuntimeError CasADi made of a KeyboardInterrupt (`error`)."""
    if _traps:
        _traps[-1].token.check(error)
    else:
        cancel.check(error)


@contextmanager
def trap(token: CancelToken | None = None, signals=SIGNALS,
         abandon: bool = True) -> Iterator[CancelToken]:
    """`signals` cancel `token` (a new one by default) within this block, the run-in-progress
    token of runtime.cancel; with `abandon`, the third ends the process. The previous
    handlers are restored after the block."""
    found = _Trap(token or CancelToken(), abandon)
    previous = {number: signal.signal(number, found.handler) for number in signals}
    _traps.append(found)
    try:
        with cancel.running(found.token):
            yield found.token
    finally:
        _traps.remove(found)
        for number, handler in previous.items():
            signal.signal(number, handler)


class guard:
    """Ctrl-C cancels `token` during this block when no trap() is active, this is the main
    thread and SIGINT has Python's default handler (a program's own handler is left alone);
    otherwise the token is only the running one. An analysis nested in another's block
    (inside a trap() or guard()) installs no handler of its own: the outer one serves both.
    The handlers are read and set through `_signal`, the C module `signal` wraps, whose
    handlers are the same objects without signal's conversion of them to enums (which cost
    several times the installs themselves, on every analysis); another thread is told by the
    install's own refusal (a ValueError), not by asking `threading` first."""

    __slots__ = ("token", "_trap", "_previous", "_reset")

    def __init__(self, token: CancelToken):
        self.token, self._trap, self._previous, self._reset = token, None, None, None

    def __enter__(self) -> CancelToken:
        if not _traps and _signal.getsignal(_SIGINT) is signal.default_int_handler:
            found = _Trap(self.token, abandon=False)
            try:
                self._previous = _signal.signal(_SIGINT, found.handler)
            except ValueError:  # not the main thread (whose handlers alone run)
                pass
            else:
                self._trap = found
                _traps.append(found)
        self._reset = cancel.enter(self.token)
        return self.token

    def __exit__(self, *exc) -> None:
        cancel.leave(self._reset)
        if self._trap is not None:
            _traps.remove(self._trap)
            _signal.signal(_SIGINT, self._previous)


@contextmanager
def saving() -> Iterator[None]:
    """Within this block a signal does not interrupt (the rows are being written)."""
    found = _traps[-1] if _traps else None
    if found is not None:
        found.saving += 1
    try:
        yield
    finally:
        if found is not None:
            found.saving -= 1
