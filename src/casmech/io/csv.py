"""results.csv per the results contract: a header row, then one row per output time."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import orjson

from casmech.core.atomic import atomic
from casmech.errors import UsageError

# numbers formatted per block of rows: a text of about 100-200 KB, whose buffers the allocator
# reuses from block to block (a text of megabytes is mapped and unmapped anew each time)
CHUNK_VALUES = 1 << 13
PIECE = 1 << 16  # bytes of whole rows per write call of CsvRows
# columns from which rows_text formats each row by itself and joins the lines: one pass over
# the text, where the whole block's text with its row separators replaced takes two (narrower
# rows cost more per row than that pass)
ROW_BY_ROW = 16


def write_csv(path: str | Path, names: list[str], values: np.ndarray) -> Path:
    """Write atomically (a reader never sees a half-written file). Numbers in the shortest form
    that reads back to the same binary64 value (0.03, not 0.029999999999999999)."""
    path = Path(path)
    values = np.atleast_2d(np.asarray(values, dtype=np.float64))
    with atomic(path, "wb") as handle:
        handle.write((",".join(names) + "\n").encode())
        rows = max(1, CHUNK_VALUES // max(1, values.shape[1]))
        for start in range(0, values.shape[0], rows):
            handle.write(rows_text(values[start:start + rows]))
    return path


class CsvRows:
    """results.csv written as the rows come: the header at once, then blocks of rows appended
    (`append`; whole rows, about PIECE bytes per write call to the OS, no Python buffer in
    between). A piece whose write fails (a full disk, a file-size limit) is cut off again
    (`os.ftruncate` to the end of the rows before it), so the file always ends at a row and
    `rows` counts the rows in it; the OSError is raised."""

    def __init__(self, path: str | Path, names: list[str]):
        self.path, self.names = Path(path), list(names)
        self.header = (",".join(self.names) + "\n").encode()
        self.handle = open(self.path, "wb", buffering=0)  # noqa: SIM115 - closed by close()
        self.end = self.rows = 0  # bytes of the header and complete rows; complete rows
        try:
            self._write(self.header, 0)
        except BaseException:
            self.handle.close()
            raise

    def append(self, values: np.ndarray) -> None:
        values = np.atleast_2d(np.asarray(values, dtype=np.float64))
        rows = max(1, CHUNK_VALUES // max(1, values.shape[1]))
        for start in range(0, values.shape[0], rows):
            block = values[start:start + rows]
            self._write(rows_text(block), len(block))

    def rewind(self) -> None:
        """Back to the header alone (an analysis that starts over)."""
        os.ftruncate(self.handle.fileno(), len(self.header))
        self.handle.seek(len(self.header))
        self.end, self.rows = len(self.header), 0

    def _write(self, data: bytes, rows: int) -> None:
        """`rows` whole rows of text, in pieces (a failure: those of the pieces written)."""
        start = 0
        while start < len(data):
            cut = data.find(b"\n", start + PIECE) + 1 or len(data)
            view = memoryview(data)[start:cut]
            try:
                while view:
                    view = view[self.handle.write(view):]
            except OSError:
                with contextlib.suppress(OSError):  # (a file it cannot cut stays as it is)
                    os.ftruncate(self.handle.fileno(), self.end)
                    self.handle.seek(self.end)
                self.rows += data.count(b"\n", 0, start)
                raise
            self.end += cut - start
            start = cut
        self.rows += rows

    def close(self, metadata=None) -> None:
        """Close the file (`metadata` is metadata.json's, written beside it by the caller)."""
        self.handle.close()


def rows_text(values: np.ndarray) -> bytes:
    """The rows as comma-separated lines. orjson writes the shortest round-trip digits of a
    float (Ryu; docs/decisions/csv-format.md), but NaN and infinities as null: rows holding
    one are written by repr (nan, inf, -inf)."""
    if values.shape[0] == 0:
        return b""
    if values.shape[1] == 0:
        return b"\n" * values.shape[0]
    finite = np.isfinite(values)
    numbers = np.ascontiguousarray(np.where(finite, values, 0.0))
    if values.shape[1] >= ROW_BY_ROW:
        lines = [orjson.dumps(row, option=orjson.OPT_SERIALIZE_NUMPY)[1:-1] for row in numbers]
    else:
        text = orjson.dumps(numbers, option=orjson.OPT_SERIALIZE_NUMPY)[2:-2]
        if finite.all():
            return text.replace(b"],[", b"\n") + b"\n"
        lines = text.split(b"],[")
    for k in np.flatnonzero(~finite.all(axis=1)):
        lines[k] = ",".join(map(repr, values[k].tolist())).encode()
    lines.append(b"")  # (the last row's newline, joined: no copy of the whole text for it)
    return b"\n".join(lines)


# Files above this size are parsed by pandas' C reader, smaller ones by numpy, which do not
# repay importing pandas (docs/decisions/csv-format.md)
PANDAS_BYTES = 8 << 20


def read_csv(path: str | Path, as_written: bool = True) -> tuple[list[str], np.ndarray]:
    """The names and the rows, every number exactly the binary64 value written; a header alone
    is 0 rows. `as_written`: a table casmech wrote as a run went (results.csv), whose last line
    without its newline is a row cut off (a run killed while it wrote: the system may end a
    write short on a fatal signal) and is not read; else (measurements from elsewhere) every
    line is. A table that is not numbers under its header is a UsageError naming the file."""
    try:
        return _read(path, as_written)
    except ValueError as error:  # (UnicodeDecodeError and pandas' ParserError are ones)
        found = _where(path)
        raise UsageError(f"{path}{found}; expected a table of numbers under a header of column "
                         f"names" if found else f"{path}: not a table of numbers under a "
                         f"header of column names ({error})") from None


def _where(path) -> str:
    """':line:column' of the first field of a table file that is not a number, or of a line
    with another count of fields than the header's ('' where none is found: the cause is
    elsewhere, e.g. the encoding)."""
    try:
        with open(path, encoding="utf-8") as handle:
            count = len(handle.readline().split(","))
            for line, text in enumerate(handle, start=2):
                fields = text.rstrip("\r\n").split(",")
                if len(fields) != count:
                    return f":{line}:1: {len(fields)} values where the header names {count}"
                column = 1
                for field in fields:
                    try:
                        float(field)
                    except ValueError:
                        return f":{line}:{column}: {field.strip()[:20]!r} is not a number"
                    column += len(field) + 1
    except (OSError, ValueError):
        pass
    return ""


def _read(path, as_written: bool) -> tuple[list[str], np.ndarray]:
    with open(path, encoding="utf-8") as handle:
        names = handle.readline().strip().split(",")
        if not handle.readline().strip():
            return names, np.zeros((0, len(names)))
    rows = _complete_rows(path) if as_written else None
    if rows == 0:
        return names, np.zeros((0, len(names)))
    if Path(path).stat().st_size > PANDAS_BYTES:
        return names, _pandas_rows(path, rows)
    return names, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2, max_rows=rows)


def _complete_rows(path) -> int | None:
    """None when the file ends with a newline, else the rows before its last line."""
    with open(path, "rb") as handle:
        handle.seek(-1, os.SEEK_END)
        if handle.read(1) == b"\n":
            return None
        handle.seek(0)
        return sum(block.count(b"\n") for block in iter(lambda: handle.read(PIECE), b"")) - 1


def _pandas_rows(path, rows: int | None = None) -> np.ndarray:
    """The rows by pandas' C parser (the first `rows`, None: all): exact by default from
    pandas 3, by its round-trip parser before (its default there may be 1 ulp off)."""
    import pandas as pd

    exact = {} if int(pd.__version__.split(".")[0]) >= 3 else {"float_precision": "round_trip"}
    return pd.read_csv(path, dtype=np.float64, keep_default_na=False, nrows=rows,
                       na_values=["nan", "-nan"], **exact).to_numpy()


def read_measurements(path: str | Path, columns: Sequence[str] | None = None):
    """(times, {column: values}) from a CSV with a `t` column (the results format)."""
    try:
        names, values = read_csv(path, as_written=False)
    except OSError as error:
        raise UsageError(f"cannot read measurements from {path}: {error}") from None
    except UsageError as error:
        raise UsageError(f"cannot read measurements from {error}") from None
    if "t" not in names:
        raise UsageError(f"{path}: the measurements need a 't' column (time) and one column per "
                         "measured output, named as in results.csv")
    columns = [n for n in names if n != "t"] if columns is None else list(columns)
    missing = [c for c in columns if c not in names]
    if missing:
        raise UsageError(f"{path}: no column '{missing[0]}'; columns: {', '.join(names)}")
    return values[:, names.index("t")], {c: values[:, names.index(c)] for c in columns}
