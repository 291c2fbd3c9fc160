"""results.csv per the results contract: a header row, then one row per output time."""

from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np


def write_csv(path: str | Path, names: list[str], values: np.ndarray) -> Path:
    """Write atomically (a reader never sees a half-written file). Numbers in the shortest form
    that reads back to the same binary64 value (Python's `repr`: 0.03, not
    0.029999999999999999)."""
    path = Path(path)
    with atomic(path, newline="") as handle:
        handle.write(",".join(names) + "\n")
        handle.writelines(",".join(map(repr, row)) + "\n"
                          for row in np.atleast_2d(values).tolist())
    return path


@contextmanager
def atomic(path: Path, **options):
    """A text file written under a temporary name of its own (two runs into one folder do not
    share it) and renamed to `path` once complete; removed if writing fails."""
    path.parent.mkdir(parents=True, exist_ok=True)
    descriptor, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.",
                                             suffix=".tmp")
    try:
        with open(descriptor, "w", **options) as handle:
            yield handle
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def read_csv(path: str | Path) -> tuple[list[str], np.ndarray]:
    """The names and the rows (exact: Python's float parsing); a header alone is 0 rows."""
    with open(path) as handle:
        names = handle.readline().strip().split(",")
        if not handle.readline().strip():
            return names, np.zeros((0, len(names)))
    values = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return names, values
