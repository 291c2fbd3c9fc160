"""The garbage collector of a command's own process (docs/decisions/cli-collector.md).

A `casmech` process imports its libraries, reads the model and builds its functions: hundreds
of thousands of objects that live until the process ends, and almost no cycles among them.
`hold` stops the collector for that part (cli.main, when the command line is the process's
own); `release` starts it again before the part that may run long and make cycles (a run's
analysis; any other command as it starts), with every object alive then moved out of its
reach (gc.freeze), and with a young generation of YOUNG_OBJECTS allocations instead of
Python's 700; `end` moves out what is left, so that the interpreter's teardown does not
traverse it once more. A process that did not `hold` (main([...]) from a caller's code) keeps
its collector as it was: `release` does nothing there.
"""

from __future__ import annotations

import gc

# The young generation's threshold once released: an analysis makes many small objects and
# few cycles, which the default (700) collected over a hundred times per run.
YOUNG_OBJECTS = 20_000
_held = []  # [True] while this process's command line holds the collector


def hold() -> None:
    """Stop the collector until `release` (the process's own command line only)."""
    gc.set_threshold(YOUNG_OBJECTS, *gc.get_threshold()[1:])
    if gc.isenabled() and not _held:
        gc.disable()
        _held.append(True)


def release() -> None:
    """Start the collector again, the objects alive now out of its reach; nothing unless
    `hold` stopped it."""
    if _held:
        _held.clear()
        gc.freeze()
        gc.enable()


def end() -> None:
    """The command is done: its objects are left to the process's exit, not collected."""
    gc.freeze()
