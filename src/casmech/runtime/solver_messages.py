"""The solvers' own messages kept out of the terminal: SUNDIALS ("At t = ..., the corrector
convergence failed ...") and CasADi ("CasADi - <date> WARNING(...)") write them through
Python's sys.stderr, often tens of lines for one failing run, while casmech's located error
already says what failed. During an analysis (api.analyze) those lines are collected for the
run's metadata (`solver_messages`, at most MAX_LINES); everything else written to stderr (a
progress bar, warnings) passes through unchanged."""

from __future__ import annotations

import io
import re
import sys
from contextlib import contextmanager

# lines the solvers start (the first two: CasADi's word of a callback that raised, a signal)
PREFIXES = ("rhs failed: ", "res failed: ", "CasADi - ", "At t = ", "At t=")
MAX_LINES = 50
# the first line of the inputs CasADi prints when a Function's evaluation raises inside
# another's (a mapped or buffered call: Function::operator() prints them unconditionally)
DUMP_HEADER = re.compile(r"^Function \S+ \(0x[0-9a-fA-F]+\)$", re.MULTILINE)


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


class collected:
    """Within the block, the solvers' lines on sys.stderr go to `kept` (module docstring); the
    block is given the filtering stream (its `count`: the solver lines seen). A class, not a
    generator's context manager: entered on every analysis."""

    __slots__ = ("kept", "_target", "_stream")

    def __init__(self, kept: list[str]):
        self.kept, self._target, self._stream = kept, None, None

    def __enter__(self) -> _Filter:
        self._target = sys.stderr
        self._stream = _Filter(self._target, self.kept)
        sys.stderr = self._stream
        return self._stream

    def __exit__(self, *exc) -> None:
        self._stream.close_line()
        sys.stderr = self._target


@contextmanager
def without_input_dumps():
    """Within the block, what is written to sys.stderr is held and passed on at its end, less
    the input dumps CasADi writes before raising an evaluation's error (DUMP_HEADER onwards)
    when a RuntimeError leaves the block: the caller handles that error (a singular saddle
    matrix's least squares, runtime.assembly.saddle_solution) and the dump, the matrices of
    a numeric solve, says nothing a user can act on."""
    target, held = sys.stderr, io.StringIO()
    sys.stderr = held
    failed = False
    try:
        yield
    except RuntimeError:
        failed = True
        raise
    finally:
        sys.stderr = target
        text = held.getvalue()
        dump = DUMP_HEADER.search(text) if failed else None
        text = text[:dump.start()] if dump else text
        if text:
            target.write(text)
