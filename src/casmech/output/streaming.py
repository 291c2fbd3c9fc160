"""The results files written while the analysis computes its rows (`casmech run`).

A ResultsWriter is the analysis' row callback (casmech.analyze's `progress`): Result.extend
hands it every block of states as it is added (its `rows_added`), and it appends the results
rows of those blocks to every file asked for (output.csv.CsvRows, output.hdf5.Hdf5Rows) once
FLUSH_VALUES numbers are pending or FLUSH_SECONDS have passed, and at the end. So the rows
computed are on disk as the run goes: a run that fails, is interrupted, is killed or meets a
full disk keeps them.

- A results row that is not finite (a reaction or the energy of a state beyond double
  precision) is not written: the rows before it are, and runtime.nonfinite.NonFinite is raised
  (exit 3), naming the time, the column and the elements.
- An OSError of a file (a full disk, a file-size limit, a read-only folder) is a WriteError
  (exit 4) naming the path and the cause; the rows written before it stay (CsvRows cuts a
  partly written block off again).
- An analysis that starts over from t0 (a new Result: runtime.auto_formulation's rp run after
  a joint one, runtime.dynamics' augmented-Lagrangian restart) rewinds the files to their
  header; `finish` rewrites them from the final Result when it is not the one streamed.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from casmech.errors import CasmechError

FLUSH_VALUES = 1 << 18  # pending results numbers (rows x columns) that make a block
FLUSH_SECONDS = 1.0  # longest a computed row waits for its block


class WriteError(CasmechError):
    """A results file could not be written (exit 4): its path, the cause, the rows kept."""

    exit_code = 4

    def __init__(self, path: Path, error: OSError, rows: int):
        self.path, self.error, self.rows = path, error, rows
        cause = error.strerror or str(error) or type(error).__name__
        kept = f"the {rows} rows written before it are kept" if rows else "no rows written"
        super().__init__(f"cannot write {path}: {cause}; {kept}")


def writing(path: Path, rows: int, action: Callable, *args):
    """`action(*args)`, an OSError of it a WriteError for `path`."""
    try:
        return action(*args)
    except OSError as error:
        raise WriteError(path, error, rows) from None


class ResultsWriter:
    """The row callback that writes the results files as the rows come (module docstring).
    `files`: the open file writers (CsvRows, Hdf5Rows); `on_row`: the callback each row's
    time is passed on to (progress, interrupts)."""

    def __init__(self, functions, files: list, reactions_frame=None,
                 on_row: Callable[[float], None] | None = None):
        from casmech.runtime.results import column_names  # (runtime imports output)

        self.functions, self.files, self.frames = functions, files, reactions_frame
        self.on_row = on_row
        self.columns = len(column_names(functions))
        self.result = None  # the runtime.results.Result whose rows are written
        self.received = 0  # its rows handed over
        self.pending: list[tuple] = []  # blocks (times, q, q_dot, q_ddot, lam) not written
        self.written = 0  # rows in the files
        self.stopped = False  # a row was not finite: nothing more is written
        self.flushed = time.monotonic()

    def __call__(self, t: float) -> None:
        if self.on_row is not None:
            self.on_row(t)

    def rows_added(self, result, times, q, q_dot, q_ddot, lam) -> None:
        """Result.extend's hand-over of a block."""
        if self.stopped:
            return
        if result is not self.result:
            self._rewind(result)
        self.pending.append((times, q, q_dot, q_ddot, lam))
        self.received += len(times)
        waiting = (self.received - self.written) * self.columns
        if waiting >= FLUSH_VALUES or time.monotonic() - self.flushed >= FLUSH_SECONDS:
            self.flush()

    def flush(self, strict: bool = True) -> None:
        """Write the pending rows; at a row that is not finite, the rows before it, then
        NonFinite (with `strict`; else stop there quietly)."""
        from casmech.runtime.nonfinite import NonFinite
        from casmech.runtime.results import Result, table

        self.flushed = time.monotonic()
        if self.stopped or not self.pending:
            return
        blocks, self.pending = self.pending, []
        states = [np.concatenate([block[k] for block in blocks]) for k in range(5)]
        names, values = table(self.functions, Result.of_rows(*states), self.frames)
        finite = np.isfinite(values).all(axis=1)
        good = len(values) if finite.all() else int(np.argmin(finite))
        for file in self.files:
            try:
                file.append(values[:good])
            except OSError as error:
                self.written = file.rows  # the rows it kept
                raise WriteError(file.path, error, file.rows) from None
        self.written += good
        if good == len(values):
            return
        self.stopped = True
        if not strict:
            return
        column = int(np.argmin(np.isfinite(values[good])))
        error = NonFinite(float(values[good, 0]), "table", values[good, column:column + 1],
                          (states[1][good], states[2][good]), self.result)
        error.explain(self.functions, names[column])
        raise error

    def finish(self, result, strict: bool = True) -> int:
        """The rows of `result` in the files (None: no rows at all): the pending ones written,
        or the files rewritten when `result` is not the Result streamed (or holds rows it was
        not handed). Returns the rows in the files."""
        if result is None or len(result) == 0:
            if self.written or self.pending:
                self._rewind(None)
            return 0
        if not self.stopped and (result is not self.result or len(result) != self.received):
            from casmech.runtime.results import STATES

            self._rewind(result)
            self.pending = [tuple(getattr(result, name) if name != "t" else
                                  np.asarray(result.times) for name in ("t", *STATES))]
            self.received = len(result)
        self.flush(strict)
        return self.written

    def _rewind(self, result) -> None:
        for file in self.files:
            writing(file.path, 0, file.rewind)
        self.result, self.received, self.pending, self.written = result, 0, [], 0
        self.stopped = False

    def close(self, metadata: dict | None = None) -> None:
        """Close every file; an HDF5 file gets `metadata` as its /metadata group."""
        for file in self.files:
            writing(file.path, self.written, file.close, metadata)

    def discard(self) -> None:
        """Close and remove the files (a failure before any row: the metadata only)."""
        for file in self.files:
            with contextlib.suppress(OSError):
                file.close()
            with contextlib.suppress(OSError):
                Path(file.path).unlink()
