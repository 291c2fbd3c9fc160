"""`casmech plot DIR/sweep.csv [OUTPUTS]`: a study's kept outputs, one panel each.

A grid study: each output against the first grid parameter, one line per value of the other
grid parameters. A sampled study (no grid): a histogram of each output. Only complete runs are
drawn; the title says how many failed. OUTPUTS default to every kept output.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from casmech.errors import UsageError, did_you_mean
from casmech.io import plot

FIRST = "run"  # sweep.csv: run, the parameters, status, wall_s, the kept outputs, reason


def is_sweep(names: Sequence[str]) -> bool:
    return bool(names) and names[0] == FIRST and "status" in names and "reason" in names


def layout(path: Path, names: Sequence[str]) -> tuple[list[str], list[str]]:
    """(grid parameters, kept outputs) of a sweep.csv: from metadata.json beside it, else the
    columns (every parameter taken as a grid axis)."""
    status = list(names).index("status")
    parameters, outputs = list(names[1:status]), list(names[status + 2:-1])
    try:
        study = json.loads((path.parent / "metadata.json").read_text())["study"]
        grid = [name for name in study["grid"] if name in parameters]
    except (OSError, ValueError, KeyError, TypeError):
        grid = parameters
    return grid, outputs


def figure(path: Path, specs: Sequence[str]):
    import pandas as pd

    table = pd.read_csv(path, keep_default_na=False, na_values=["nan", "NaN", ""])
    grid, outputs = layout(path, list(table.columns))
    chosen = list(specs) or outputs
    for name in chosen:
        if name not in outputs:
            hint = did_you_mean(name, outputs)
            raise UsageError(f"'{name}' is not a kept output of {path.name}"
                             f"{f'; {hint}' if hint else ''} (kept: {', '.join(outputs)})")
    done = table[table["status"] == "complete"]
    Figure = plot.matplotlib_figure()  # noqa: N806 - a class
    fig = Figure(figsize=(8, 1.2 + 3.0 * len(chosen)), layout="constrained")
    axes = fig.subplots(len(chosen), 1, squeeze=False)[:, 0]
    for ax, name in zip(axes, chosen, strict=True):
        if grid:
            _lines(ax, done, grid, name)
        else:
            ax.hist(done[name].dropna().to_numpy(), bins=_bins(len(done)))
            ax.set_xlabel(name)
            ax.set_ylabel("runs")
        ax.grid(True, alpha=0.3)
    failed = len(table) - len(done)
    fig.suptitle(f"{path.name}: {len(done)} runs" + (f", {failed} failed (not drawn)"
                                                      if failed else ""))
    return fig


def _lines(ax, done, grid: list[str], name: str) -> None:
    x, others = grid[0], grid[1:]
    groups = done.groupby(others) if others else [((), done)]
    for key, group in groups:
        group = group.sort_values(x)
        key = key if isinstance(key, tuple) else (key,)
        label = ", ".join(f"{n} = {v:g}" for n, v in zip(others, key, strict=True)) or None
        ax.plot(group[x], group[name], marker="o", label=label)
    ax.set_xlabel(x)
    ax.set_ylabel(name)
    if others:
        ax.legend(fontsize="small")


def _bins(count: int) -> int:
    """Square-root choice, between 5 and 50."""
    return int(np.clip(np.sqrt(max(count, 1)), 5, 50))
