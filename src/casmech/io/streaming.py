"""The results files written while the analysis computes its rows (`casmech run`).

A ResultsWriter rides on the analysis' row callback (casmech.analyze's `progress`, given its
`rows_added`): Result.extend hands it every block of states as it is added, and it appends the
results rows of those blocks to every file asked for (output.csv.CsvRows,
output.hdf5.Hdf5Rows) in blocks of whole mapped calls of the results row (about FLUSH_VALUES
numbers), or what is pending once FLUSH_SECONDS have passed, and the rest at the end. So the
rows computed are on disk as the run goes: a run that fails, is interrupted, is killed or
meets a full disk keeps them.

- A results row that is not finite (a reaction or the energy of a state beyond double
  precision) is not written: the rows before it are, and runtime.nonfinite.NonFinite is raised
  (exit 3), naming the time, the column and the elements.
- An OSError of a file (a full disk, a file-size limit, a read-only folder) is a WriteError
  (exit 4) naming the path and the cause; the rows written before it stay (CsvRows cuts a
  partly written block off again, Hdf5Rows commits nothing it has no room for).
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

FLUSH_VALUES = 1 << 18  # results numbers (rows x columns) of a block written at once
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
    """Writes the results files as the rows come (module docstring): `watching(on_row)` is
    the analysis' row callback. `files`: the open file writers (CsvRows, Hdf5Rows)."""

    def __init__(self, functions, files: list, reactions_frame=None):
        from casmech.runtime.buffers import BLOCK  # (runtime imports output)
        from casmech.runtime.results import column_names

        self.functions, self.files, self.frames = functions, files, reactions_frame
        columns = len(column_names(functions))
        # rows per block: whole blocks of the results row's mapped calls (ColumnCall keeps a
        # map per block length), about FLUSH_VALUES numbers
        self.block = max(BLOCK, FLUSH_VALUES // columns // BLOCK * BLOCK)
        self.result = None  # the runtime.results.Result whose rows are written
        self.received = 0  # its rows handed over
        self.pending: list[tuple] = []  # blocks (times, q, q_dot, q_ddot, lam) not written
        self.written = 0  # rows in the files
        self.stopped = False  # a row was not finite: nothing more is written
        self.flushed = time.monotonic()

    def watching(self, on_row: Callable[[float], None]) -> Callable[[float], None]:
        """`on_row` (the row callback: progress, interrupts), given this writer's `rows_added`:
        the analysis' `progress`, calling no more per row than `on_row` does."""
        on_row.rows_added = self.rows_added
        return on_row

    def rows_added(self, result, times, q, q_dot, q_ddot, lam) -> None:
        """Result.extend's hand-over of a block."""
        if self.stopped:
            return
        if result is not self.result:
            self._rewind(result)
        self.pending.append((times, q, q_dot, q_ddot, lam))
        self.received += len(times)
        waiting = sum(len(block[0]) for block in self.pending)
        if waiting >= self.block:
            self.flush(whole=True)
        elif time.monotonic() - self.flushed >= FLUSH_SECONDS:
            self.flush()

    def flush(self, strict: bool = True, whole: bool = False) -> None:
        """Write the pending rows (`whole`: as many as fill whole blocks, the rest left
        pending); at a row that is not finite, the rows before it, then NonFinite (with
        `strict`; else stop there quietly)."""
        from casmech.runtime.nonfinite import NonFinite
        from casmech.runtime.results import Result, table, with_fixed

        self.flushed = time.monotonic()
        if self.stopped or not self.pending:
            return
        states = [np.concatenate([block[k] for block in self.pending]) for k in range(5)]
        count = len(states[0]) // self.block * self.block if whole else len(states[0])
        self.pending = [tuple(state[count:] for state in states)] if count < len(states[0]) \
            else []
        states = [state[:count] for state in states]
        names, values = table(self.functions, Result.of_rows(*states), self.frames)
        values = with_fixed(self.result, names, values, self.written)
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
