"""`--full`: every run's results table in one HDF5 file, written as the runs finish.

Layout of DIR/runs.h5:
    /columns            the results contract's column names (once; every run has the same)
    /run_000000 ...     one group per finished run, named by its index in the study:
        results         float64 [rows x columns] (no rows when a run failed before its first)
        attributes      the run's parameter values, status, reason, wall_s

Written under a temporary name and renamed when closed (core.atomic), so an interrupted
study leaves a complete file of the runs that finished.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from casmech.io.hdf5 import h5py
from casmech.study.runner import Outcome


def group_name(index: int) -> str:
    return f"run_{index:06d}"


class FullWriter:
    def __init__(self, path: Path, parameters: Sequence[str]):
        self.h5 = h5py()
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        descriptor, self.temporary = tempfile.mkstemp(dir=self.path.parent,
                                                      prefix=f".{self.path.name}.", suffix=".tmp")
        os.close(descriptor)
        self.file = self.h5.File(self.temporary, "w")
        self.parameters = tuple(parameters)

    def add(self, index: int, outcome: Outcome) -> None:
        if outcome.names is not None and "columns" not in self.file:
            self.file.create_dataset("columns", data=outcome.names,
                                     dtype=self.h5.string_dtype("utf-8"))
        group = self.file.create_group(group_name(index))
        table = outcome.table if outcome.table is not None else np.zeros((0, 0))
        group.create_dataset("results", data=np.asarray(table, float))
        for name in self.parameters:
            group.attrs[name] = float(outcome.values[name])
        group.attrs.update(status=outcome.status, reason=outcome.reason, wall_s=outcome.wall_s)

    def close(self) -> None:
        self.file.close()
        os.replace(self.temporary, self.path)


def read_run(path: str | Path, index: int) -> tuple[list[str], np.ndarray, dict]:
    """(column names, table, attributes) of one run of a runs.h5."""
    h5 = h5py()
    with h5.File(path, "r") as handle:
        names = [n.decode() if isinstance(n, bytes) else str(n) for n in handle["columns"][()]]
        group = handle[group_name(index)]
        return names, group["results"][()], dict(group.attrs)
