"""Results as pandas DataFrames, and a summary of a run for `repr` and notebooks.

A results frame holds the results contract's table (docs/format.md): index `t` (float seconds),
the other columns in contract order under their contract names, float64. Its `attrs`:

    attrs["units"]      column name (t included) -> SI unit ("m", "rad/s", "N m", "-", ...)
    attrs["metadata"]   the run's metadata dict (metadata.json / results.h5's /metadata group;
                        for a Result of the API, its own metadata)

pandas is imported when a frame is made (a Result's repr does not need it). Reading results
files into the same layout: casmech.io.frames.load_results.
"""

from __future__ import annotations

import html
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from casmech.core.columns import units

if TYPE_CHECKING:
    import pandas as pd


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
