"""Cancelling a run: a token the analyses poll, and the window in which a signal stops a solver
call at once.

A CancelToken is cancelled by `cancel()`: a signal handler (runtime.interrupts), a callback,
another thread. The analyses poll it (`poll()`, the token of the run in progress: `running`)
between solver calls, between the blocks of rows they compute and in their iteration loops;
a cancelled token raises errors.Interrupted (an AnalysisError, so the rows computed so far
come with it in `partial`, and a KeyboardInterrupt). A run whose rows are all computed is
complete, whenever the token was cancelled.

Inside a solver call (an integrator's evaluation, `solving()`), SUNDIALS asks CasADi whether
to stop, which runs Python's signal handlers: runtime.interrupts' handler raises there when
`armed()`, so a signal stops IDAS or CVODES within one residual evaluation; CasADi turns that
into a RuntimeError, and the code catching it calls `check(error)` before taking it for a
solver failure.
"""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

from casmech.errors import Interrupted


class CancelToken:
    """Whether, and by which signal, a run was asked to stop (once cancelled, it stays so:
    a token per run)."""

    def __init__(self) -> None:
        self.signum: int | None = None

    def cancel(self, signum: int = signal.SIGINT) -> None:
        """Ask the run to stop (the first request's signal is kept)."""
        if self.signum is None:
            self.signum = int(signum)

    @property
    def cancelled(self) -> bool:
        return self.signum is not None

    def check(self, error: BaseException | None = None) -> None:
        """Raise Interrupted when cancelled; or for a RuntimeError CasADi made of a
        KeyboardInterrupt (`error`)."""
        if self.signum is not None:
            raise Interrupted(self.signum)
        if error is not None and "KeyboardInterrupt" in str(error):
            raise Interrupted(signal.SIGINT) from None


_running: ContextVar[CancelToken | None] = ContextVar("casmech_cancel", default=None)
_armed = [0]  # solving() blocks entered and not left (signals reach the main thread only)


def current() -> CancelToken | None:
    """The token of the run in progress in this thread, if any."""
    return _running.get()


@contextmanager
def running(token: CancelToken) -> Iterator[CancelToken]:
    """`token` is the one `poll` and `check` see within this block."""
    reset = _running.set(token)
    try:
        yield token
    finally:
        _running.reset(reset)


def enter(token: CancelToken):
    """Make `token` the running one until leave(the value returned) (running() as calls)."""
    return _running.set(token)


def leave(reset) -> None:
    """Undo the enter() that returned `reset`."""
    _running.reset(reset)


def poll() -> None:
    """Raise Interrupted if the run in progress was cancelled."""
    token = _running.get()
    if token is not None:
        token.check()


def check(error: BaseException | None = None) -> None:
    """poll(), and Interrupted for a RuntimeError CasADi made of a KeyboardInterrupt."""
    token = _running.get()
    if token is not None:
        token.check(error)
    elif error is not None and "KeyboardInterrupt" in str(error):
        raise Interrupted(signal.SIGINT) from None


def armed() -> bool:
    """Whether a solver call is being evaluated (a signal may stop it at once)."""
    return _armed[0] > 0


@contextmanager
def solving() -> Iterator[None]:
    """Around the evaluation of a solver call only (runtime.buffers)."""
    arm()
    try:
        yield
    finally:
        disarm()


def arm() -> None:
    """A solver call's evaluation begins (solving() as calls: disarm() after it, always)."""
    _armed[0] += 1


def disarm() -> None:
    """The evaluation arm() announced has ended."""
    _armed[0] -= 1
