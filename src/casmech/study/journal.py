"""sweep.csv as runs finish: each row appended and flushed as its run arrives, so a sweep
killed by any signal (SIGKILL included) keeps every run that finished; `--resume` reads the
rows back and runs only the missing ones.

While a sweep runs, sweep.csv holds its rows in the order they finished (`run` is each one's
index in the study); the finished sweep rewrites it in run order (study.sweep.write). A line
cut short by a kill is dropped when the file is read back. Numbers are written as Python's
repr (they read back as the same doubles), NaN as an empty field, as pandas writes them.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

from casmech.errors import UsageError, escape

TEXT = ("status", "reason")  # the columns that are not numbers ("run" is an integer)


def _field(value) -> str:
    if isinstance(value, float):
        return "" if math.isnan(value) else repr(value)
    return str(value)


def _value(column: str, text: str):
    if column in TEXT:
        return text
    if column == "run":
        return int(text)
    return float(text) if text != "" else float("nan")


class Journal:
    """The results file of a running sweep, appended as runs arrive."""

    def __init__(self, path: Path, columns: Sequence[str], rows: Sequence[Mapping] = ()):
        """A new file with the header and `rows` (those of a resumed sweep)."""
        self.path, self.columns = Path(path), list(columns)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        temporary = self.path.with_name(f".{self.path.name}.resume")
        with open(temporary, "w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle)
            writer.writerow(self.columns)
            for row in rows:
                writer.writerow([_field(row[c]) for c in self.columns])
        os.replace(temporary, self.path)
        self.handle = open(self.path, "a", newline="", encoding="utf-8")  # noqa: SIM115
        self.writer = csv.writer(self.handle)

    def add(self, row: Mapping) -> None:
        self.writer.writerow([_field(row[c]) for c in self.columns])
        self.handle.flush()  # in the kernel's hands: a killed process loses nothing

    def close(self) -> None:
        self.handle.close()


def read(path: Path, columns: Sequence[str], points: Sequence[Mapping[str, float]],
         parameters: Sequence[str]) -> list[dict]:
    """The finished rows of an earlier run of the same study (a usage error for a file of
    another study: other columns, or a run whose parameter values differ)."""
    shown = escape(path)
    if not path.is_file():
        raise UsageError(f"--resume: {shown} does not exist; start the study without --resume")
    with open(path, newline="", encoding="utf-8", errors="replace") as handle:
        lines = list(csv.reader(handle))
    if not lines or lines[0] != list(columns):
        raise UsageError(f"--resume: {shown} is not this study's results file (its columns "
                         f"differ: expected {', '.join(columns)})")
    rows: dict[int, dict] = {}
    for number, line in enumerate(lines[1:], start=2):
        try:
            row = {c: _value(c, text) for c, text in zip(columns, line, strict=True)}
        except ValueError:
            if number == len(lines):
                continue  # the last line, cut short by a kill
            raise UsageError(f"--resume: {shown}:{number}: not a row of this study") from None
        index = row["run"]
        if not 0 <= index < len(points) or any(
                row[name] != points[index][name] for name in parameters):
            raise UsageError(f"--resume: {shown}:{number}: run {index} has other parameter "
                             "values than this study's; the file belongs to another study "
                             "(its grid, samples or seed differ)")
        rows[index] = row
    return [rows[k] for k in sorted(rows)]
