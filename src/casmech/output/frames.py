"""Results as pandas DataFrames, and a summary of a run for `repr` and notebooks.

A results frame holds the results contract's table (docs/format.md): index `t` (float seconds),
the other columns in contract order under their contract names, float64. Its `attrs`:

    attrs["units"]      column name (t included) -> SI unit ("m", "rad/s", "N m", "-", ...)
    attrs["metadata"]   the run's metadata dict (metadata.json / results.h5's /metadata group;
                        for a Result of the API, its own metadata)

`load_results(DIR)` reads DIR/results.csv (with DIR/metadata.json) or DIR/results.h5; the API's
`Result.to_dataframe()` builds the same layout from the states. pandas is imported when a frame
is made (a Result's repr does not need it).
"""

from __future__ import annotations

import html
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from casmech.errors import UsageError
from casmech.output.plot import quantity

if TYPE_CHECKING:
    import pandas as pd

RESULTS_FILES = {"csv": "results.csv", "hdf5": "results.h5"}  # format -> file in a results DIR


def units(names: Sequence[str]) -> dict[str, str]:
    """The SI unit of every results column, from its name (as the plots label their axes)."""
    return {name: quantity(name)[1] for name in names}


def frame(names: Sequence[str], values: np.ndarray, metadata: Mapping | None = None
          ) -> pd.DataFrame:
    """The results table as a DataFrame indexed by t (names[0] must be "t")."""
    import pandas as pd

    if not names or names[0] != "t":
        raise ValueError(f"a results table starts with column 't', got {list(names[:1])}")
    values = np.asarray(values, float).reshape(-1, len(names))
    index = pd.Index(values[:, 0], name="t", dtype=float)
    data = pd.DataFrame(values[:, 1:], index=index, columns=list(names[1:]), dtype=float)
    data.attrs["units"] = units(names)
    data.attrs["metadata"] = dict(metadata or {})
    return data


def _csv(path: Path) -> tuple[list[str], np.ndarray, dict]:
    """results.csv (exact: Python's float parsing) and the metadata.json beside it, if any."""
    from casmech.output.csv import read_csv
    from casmech.output.metadata import read_json

    names, values = read_csv(path)
    beside = path.with_name("metadata.json")
    metadata = read_json(beside) if beside.is_file() else {}
    return names, values, metadata


def _hdf5(path: Path) -> tuple[list[str], np.ndarray, dict]:
    from casmech.output.hdf5 import read_hdf5, read_hdf5_metadata

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


def summary(model: str, analysis: str, times: Sequence[float], status: str,
            columns: int, extra: Mapping[str, object] = ()) -> dict[str, str]:
    """The facts a Result's repr shows, as text: model, analysis, rows, time span, status,
    column count, then `extra` (e.g. formulation, mode)."""
    span = f"{times[0]:.6g} .. {times[-1]:.6g} s" if len(times) else "none"
    facts = {"model": model, "analysis": analysis, "rows": str(len(times)), "time span": span,
             "status": status, "columns": str(columns)}
    facts.update({key: str(value) for key, value in dict(extra).items()})
    return facts


def summary_text(facts: Mapping[str, str]) -> str:
    return "Result(" + ", ".join(f"{key}: {value}" for key, value in facts.items()) + ")"


def summary_html(facts: Mapping[str, str]) -> str:
    """A two-column HTML table (Jupyter's rich display)."""
    rows = "".join(f"<tr><th style=\"text-align:left\">{html.escape(key)}</th>"
                   f"<td style=\"text-align:left\">{html.escape(value)}</td></tr>"
                   for key, value in facts.items())
    return f"<table><caption>casmech Result</caption>{rows}</table>"
