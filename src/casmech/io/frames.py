"""Results files read back as DataFrames: `load_results(DIR)` reads DIR/results.csv (with
DIR/metadata.json) or DIR/results.h5 into the layout of casmech.runtime.frames (the API's
`Result.to_dataframe()` builds the same layout from the states)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from casmech.errors import UsageError
from casmech.runtime.frames import frame

if TYPE_CHECKING:
    import pandas as pd

RESULTS_FILES = {"csv": "results.csv", "hdf5": "results.h5"}  # format -> file in a results DIR


def _csv(path: Path) -> tuple[list[str], np.ndarray, dict]:
    """results.csv (exact: Python's float parsing) and the metadata.json beside it, if any."""
    from casmech.io.csv import read_csv
    from casmech.io.metadata import read_json

    names, values = read_csv(path)
    beside = path.with_name("metadata.json")
    metadata = read_json(beside) if beside.is_file() else {}
    return names, values, metadata


def _hdf5(path: Path) -> tuple[list[str], np.ndarray, dict]:
    from casmech.io.hdf5 import read_hdf5, read_hdf5_metadata

    names, values = read_hdf5(path)
    return names, values, read_hdf5_metadata(path)


READERS = {".csv": _csv, ".h5": _hdf5, ".hdf5": _hdf5}  # results file suffix -> reader


def results_file(path: str | Path, format: str | None = None) -> Path:  # noqa: A002
    """The results file `path` names: itself, or in a results folder the file of `format`
    (default: results.csv when present, else results.h5)."""
    path = Path(path)
    if path.is_file():
        return path
    if not path.is_dir():
        raise UsageError(f"{path}: no such results folder or file")
    if format is not None and format not in RESULTS_FILES:
        raise UsageError(f"format '{format}' is not one of {', '.join(RESULTS_FILES)}")
    for name in [RESULTS_FILES[format]] if format else RESULTS_FILES.values():
        if (path / name).is_file():
            return path / name
    raise UsageError(f"{path}: holds no {' or '.join(RESULTS_FILES.values())} "
                     "(write one with `casmech run MODEL --out DIR`)")


def load_results(path: str | Path, format: str | None = None) -> pd.DataFrame:  # noqa: A002
    """A run's results as a DataFrame: index t, the contract's columns, attrs["units"] and
    attrs["metadata"]. `path`: a results folder (`casmech run --out DIR`) or a results.csv /
    results.h5 file; `format` ("csv" or "hdf5") picks the file in a folder holding both."""
    file = results_file(path, format)
    reader = READERS.get(file.suffix.lower())
    if reader is None:
        raise UsageError(f"{file}: not a results file (expected {', '.join(READERS)})")
    names, values, metadata = reader(file)
    return frame(names, values, metadata)


