"""results.h5: the results table plus the run's metadata, in one HDF5 file (h5py, imported on
use).

Layout:
    /results    float64 [rows x columns], the results contract's table
    /columns    the column names, in contract order (variable-length UTF-8 strings)
    /metadata   casmech.io.metadata's dict: a nested dict is a group, a value an attribute,
                except the model text, a string dataset /metadata/model/text; a key's '/'
                (file paths under `files`) is written %2F and '%' %25 (HDF5 names hold no '/')
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from casmech.core.atomic import replaced
from casmech.errors import UsageError
from casmech.io.staged import StagedFile

DATASETS = ("text",)  # metadata keys stored as datasets (long), not attributes


def h5py():
    try:
        import h5py as module
    except ImportError:
        raise UsageError("HDF5 output needs h5py, a dependency of casmech missing here; install "
                         "it with: pip install h5py") from None
    return module


def write_hdf5(path: str | Path, names: list[str], values: np.ndarray,
               metadata: Mapping | None = None) -> Path:
    """Write atomically (core.atomic)."""
    h5 = h5py()
    path = Path(path)
    strings = h5.string_dtype("utf-8")
    with replaced(path) as temporary, h5.File(temporary, "w") as handle:
        table = np.atleast_2d(np.asarray(values, float)).reshape(-1, len(names))
        handle.create_dataset("results", data=table)
        handle.create_dataset("columns", data=np.array(names, dtype=object), dtype=strings)
        _write_group(handle.create_group("metadata"), metadata or {}, strings)
    return path


class Hdf5Rows:
    """results.h5 written as the rows come: /columns at once, /results a resizable dataset
    (chunks of ROWS_PER_CHUNK rows) that each block extends, each block committed to the disk
    (output.staged: a commit that finds no room writes nothing, and the file stays readable
    with the rows before); /metadata when the run ends (`close`). A failed commit is raised
    as its OSError."""

    ROWS_PER_CHUNK = 1024

    def __init__(self, path: str | Path, names: list[str]):
        h5 = h5py()
        self.path, self.names = Path(path), list(names)
        self.strings = h5.string_dtype("utf-8")
        self.file = StagedFile(self.path)
        self.handle = h5.File(self.file, "w")
        self.table = self.handle.create_dataset(
            "results", shape=(0, len(names)), maxshape=(None, len(names)), dtype=float,
            chunks=(self.ROWS_PER_CHUNK, max(1, len(names))))
        self.handle.create_dataset("columns", data=np.array(names, dtype=object),
                                   dtype=self.strings)
        self.rows = 0  # rows committed to the disk
        self._commit(0)

    def append(self, values: np.ndarray) -> None:
        """The rows, committed in pieces of ROWS_PER_CHUNK (a failure keeps those before)."""
        values = np.atleast_2d(np.asarray(values, float)).reshape(-1, len(self.names))
        for start in range(0, len(values), self.ROWS_PER_CHUNK):
            piece = values[start:start + self.ROWS_PER_CHUNK]
            rows = self.table.shape[0]
            self.table.resize(rows + len(piece), axis=0)
            self.table[rows:] = piece
            self._commit(rows + len(piece))

    def rewind(self) -> None:
        self.table.resize(0, axis=0)
        self._commit(0)

    def _commit(self, rows: int) -> None:
        self.handle.flush()
        self.file.commit()
        if self.file.failure is not None:
            raise self.file.failure
        self.rows = rows

    def close(self, metadata: Mapping | None = None) -> None:
        """Write /metadata (when given), close the file, commit it."""
        try:
            if metadata is not None and self.file.failure is None:
                if "metadata" in self.handle:
                    del self.handle["metadata"]
                _write_group(self.handle.create_group("metadata"), metadata, self.strings)
            self.handle.close()
            self.file.commit()
        finally:
            self.file.close()
        if self.file.failure is not None:
            raise self.file.failure


def _name(key: str) -> str:
    return key.replace("%", "%25").replace("/", "%2F")


def _key(name: str) -> str:
    return name.replace("%2F", "/").replace("%25", "%")


def _write_group(group, mapping: Mapping, strings) -> None:
    for key, value in ((_name(k), v) for k, v in mapping.items()):
        if isinstance(value, Mapping):
            _write_group(group.create_group(key), value, strings)
        elif key in DATASETS:
            group.create_dataset(key, data=str(value), dtype=strings)
        else:
            group.attrs[key] = "" if value is None else value


def read_hdf5(path: str | Path) -> tuple[list[str], np.ndarray]:
    """The names and the rows of a results.h5; a file that is not one (not HDF5, without the
    datasets, their shapes not a table of its columns, larger than a run writes) is a
    UsageError naming it, read no further than its datasets' shapes."""
    from casmech.schema.limits import MAX_VALUES

    try:
        with h5py().File(path, "r") as handle:
            columns, results = handle["columns"], handle["results"]
            if columns.ndim != 1 or results.ndim != 2 or results.shape[1] != columns.shape[0]:
                raise ValueError(f"'results' of shape {results.shape} is not a table of the "
                                 f"{columns.shape} 'columns'")
            if results.size > MAX_VALUES:
                raise ValueError(f"{results.size} values, more than a run writes ({MAX_VALUES})")
            names = [str(name) for name in columns.asstr()[()]]
            return names, np.array(results[()], float)
    except (OSError, KeyError, TypeError, ValueError) as error:
        raise UsageError(f"{path}: not a results.h5 of casmech run ({error})") from None


def read_hdf5_metadata(path: str | Path) -> dict:
    with h5py().File(path, "r") as handle:
        return _read_group(handle["metadata"])


def _read_group(group) -> dict:
    data = {_key(key): _plain(value) for key, value in group.attrs.items()}
    for key, item in group.items():
        data[_key(key)] = _read_group(item) if hasattr(item, "keys") else item.asstr()[()]
    return data


def _plain(value):
    """h5py's numpy scalars and arrays as the Python values they were written from."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value.item() if isinstance(value, np.generic) else value
