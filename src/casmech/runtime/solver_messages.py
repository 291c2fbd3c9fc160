"""The solvers' own messages kept out of the terminal: SUNDIALS ("At t = ..., the corrector
convergence failed ...") and CasADi ("CasADi - <date> WARNING(...)") write them through
Python's sys.stderr, often tens of lines for one failing run, while casmech's located error
already says what failed. During an analysis (api.analyze) those lines are collected for the
run's metadata (`solver_messages`, at most MAX_LINES); everything else written to stderr (a
progress bar, warnings) passes through unchanged."""

from __future__ import annotations

import io
import sys
from contextlib import contextmanager

# lines the solvers start (the first two: CasADi's word of a callback that raised, a signal)
PREFIXES = ("rhs failed: ", "res failed: ", "CasADi - ", "At t = ", "At t=")
MAX_LINES = 50


class _Filter(io.TextIOBase):
    """A text stream that keeps the solvers' lines and passes every other line to `target`.
    Text arrives in fragments; a line is held only while it may still become a solver line."""

    def __init__(self, target, kept: list[str]):
        self.target, self.kept = target, kept
        self.line, self.mode = "", None  # mode: None (undecided), "keep" or "pass"
        self.count = 0

    def writable(self) -> bool:
        return True

    def isatty(self) -> bool:  # a progress bar asks whether stderr is a terminal
        return self.target.isatty()

    def fileno(self) -> int:
        return self.target.fileno()

    @property
    def encoding(self):
        return getattr(self.target, "encoding", "utf-8")

    def write(self, text: str) -> int:
        for piece in text.splitlines(keepends=True):
            self._piece(piece)
        return len(text)

    def _piece(self, piece: str) -> None:
        if self.mode == "pass":
            self.target.write(piece)
        else:
            self.line += piece
            if self.mode is None:
                if self.line.startswith(PREFIXES):
                    self.mode = "keep"
                elif not any(prefix.startswith(self.line.rstrip("\n")) for prefix in PREFIXES):
                    self.mode = "pass"
                    self.target.write(self.line)
                    self.line = ""
        if piece.endswith("\n"):
            if self.mode == "keep":
                self.count += 1
                if len(self.kept) < MAX_LINES:
                    self.kept.append(self.line.rstrip("\n"))
            elif self.mode is None:
                self.target.write(self.line)
            self.line, self.mode = "", None

    def close_line(self) -> None:
        """At the end: a held fragment that never became a solver line is written out."""
        if self.mode != "keep" and self.line:
            self.target.write(self.line)
        self.line, self.mode = "", None

    def flush(self) -> None:
        self.target.flush()


@contextmanager
def collected(kept: list[str]):
    """Within the block, the solvers' lines on sys.stderr go to `kept` (module docstring)."""
    target = sys.stderr
    stream = _Filter(target, kept)
    sys.stderr = stream
    try:
        yield stream
    finally:
        stream.close_line()
        sys.stderr = target
