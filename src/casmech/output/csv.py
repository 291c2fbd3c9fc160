"""results.csv per the results contract: a header row, then one row per output time."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from casmech.output.atomic import atomic


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


def read_csv(path: str | Path) -> tuple[list[str], np.ndarray]:
    """The names and the rows (exact: Python's float parsing); a header alone is 0 rows."""
    with open(path) as handle:
        names = handle.readline().strip().split(",")
        if not handle.readline().strip():
            return names, np.zeros((0, len(names)))
    values = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return names, values
