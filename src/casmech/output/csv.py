"""results.csv per the results contract: a header row, then one row per output time."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np


def write_csv(path: str | Path, names: list[str], values: np.ndarray) -> Path:
    """Write atomically (a reader never sees a half-written file). Numbers in the shortest form
    that reads back to the same binary64 value (Python's `repr`: 0.03, not
    0.029999999999999999)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(path.name + ".tmp")
    with open(temporary, "w", newline="") as handle:
        handle.write(",".join(names) + "\n")
        handle.writelines(",".join(map(repr, row)) + "\n"
                          for row in np.atleast_2d(values).tolist())
    os.replace(temporary, path)
    return path


def read_csv(path: str | Path) -> tuple[list[str], np.ndarray]:
    with open(path) as handle:
        names = handle.readline().strip().split(",")
    values = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return names, values
