"""Plots of a results table (matplotlib, a dependency imported only when plotting).

A selection is a list of specs: column names, globs (`crank.*`) or presets (PRESETS). The chosen
columns are drawn against t, one panel per physical quantity (read from the column's suffix), with
SI units on the axes, a title per panel and a legend.
"""

from __future__ import annotations

import difflib
import fnmatch
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from casmech.core.columns import JOINT_COLUMNS, QUANTITIES, joint_quantity, quantity  # noqa: F401
from casmech.core.states import JOINT_QUANTITIES
from casmech.elements import coordinate_kinds  # noqa: F401 - fills JOINT_QUANTITIES, QUANTITIES
from casmech.errors import UsageError

LOG_SCALE = {"constraint violation"}  # quantities drawn on a logarithmic axis
PANEL_HEIGHT = 2.8  # [in] of a panel with a short legend
LEGEND_ROWS, LEGEND_COLUMNS = 16, 3  # a legend's entries per column before it widens, columns
LOG_FLOOR = 1e-16  # below this a constraint violation is round-off
SAVE_SUFFIXES = (".png", ".pdf", ".svg")


def _positions(names: Sequence[str], _argument: str) -> list[str]:
    return [n for n in names if "." in n and n.rsplit(".", 1)[1] in ("x", "y", "z")]


def _reactions(names: Sequence[str], joint: str) -> list[str]:
    columns = [f"{joint}.{c}" for c in JOINT_COLUMNS]
    if all(c in names for c in columns):
        return columns
    joints = _joints(names)
    close = difflib.get_close_matches(joint, joints, n=3, cutoff=0.5)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    raise UsageError(f"reactions:{joint}: no joint '{joint}' in the results{hint} "
                     f"(joints: {', '.join(joints) or 'none'})")


# preset -> columns(names, argument); an argument follows a colon (reactions:JOINT)
PRESETS: dict[str, Callable[[Sequence[str], str], list[str]]] = {
    "positions": _positions,
    "energy": lambda names, _: ["energy"],
    "reactions": _reactions,
    "constraints": lambda names, _: ["constraint_violation"],
}
PRESET_HELP = "positions, energy, reactions:JOINT, constraints"


def select(names: Sequence[str], specs: Sequence[str]) -> list[str]:
    """The columns the specs name, in order, without repeats and without t."""
    chosen: list[str] = []
    for spec in specs:
        chosen += _columns(names, spec)
    return [c for c in dict.fromkeys(chosen) if c != "t"]


def _columns(names: Sequence[str], spec: str) -> list[str]:
    preset, _, argument = spec.partition(":")
    if preset in PRESETS and (argument or preset != "reactions"):
        return PRESETS[preset](names, argument)
    if spec == "reactions":
        raise UsageError(f"the preset reactions needs a joint: reactions:JOINT "
                         f"(joints: {', '.join(_joints(names)) or 'none'})")
    if any(char in spec for char in "*?["):
        matches = fnmatch.filter(names, spec)
        if matches:
            return matches
        raise UsageError(f"no column matches '{spec}'{_did_you_mean(names, spec)}")
    if spec in names:
        return [spec]
    raise UsageError(f"unknown column or preset '{spec}'{_did_you_mean(names, spec)} "
                     f"(presets: {PRESET_HELP}; globs such as 'crank.*' select several columns)")


def _joints(names: Sequence[str]) -> list[str]:
    return sorted({n.rsplit(".", 1)[0] for n in names if n.endswith(".fx")})


def _did_you_mean(names: Sequence[str], spec: str) -> str:
    candidates = list(dict.fromkeys([*names, *PRESETS]))
    close = difflib.get_close_matches(spec.replace("*", ""), candidates, n=4, cutoff=0.6)
    return f"; did you mean {', '.join(close)}?" if close else ""


REACTIONS = {f"{kind}{axis}" for kind in "ft" for axis in "xyz"}  # a joint's reaction columns


def panel_key(column: str, frames: Mapping[str, str] | None = None,
              joints: frozenset[str] = frozenset(),
              outputs: Mapping[str, str | None] | None = None) -> tuple[str, str, str]:
    """The column's quantity (a joint state's, of a joint among `joints`, by its attribute:
    a spherical joint's e0 and wx are relative, not a body's; an output's, `outputs`: name
    -> its unit, each its own panel); a joint's reaction in another frame than the global axes
    (the run's metadata `reaction_frames`: joint -> frame) gets its own panel, titled by its
    frame."""
    if outputs and column in outputs:
        return column, outputs[column] or "?", f"output {column}"
    joint, _, suffix = column.rpartition(".")
    is_state = joint in joints and suffix in JOINT_QUANTITIES
    name, unit, heading = joint_quantity(column) if is_state else quantity(column)
    frame = (frames or {}).get(joint, "global")
    if suffix in REACTIONS and frame != "global":
        heading = heading.replace("(global)", f"({frame} frame of each joint)")
    return name, unit, heading


def panels(columns: Sequence[str], frames: Mapping[str, str] | None = None,
           joints: frozenset[str] = frozenset(), outputs: Mapping[str, str | None] | None = None
           ) -> dict[tuple[str, str, str], list[str]]:
    """Columns grouped by quantity (and reaction frame), in order of first appearance."""
    grouped: dict[tuple[str, str, str], list[str]] = {}
    for column in columns:
        grouped.setdefault(panel_key(column, frames, joints, outputs), []).append(column)
    return grouped


def figure(names: Sequence[str], values: np.ndarray, specs: Sequence[str], title: str = "",
           frames: Mapping[str, str] | None = None,
           outputs: Mapping[str, str | None] | None = None):
    """A matplotlib Figure of the selected columns against t (one panel per quantity; reaction
    columns by the frame `frames` names for their joint, global when not named; the model's
    outputs with the units `outputs` gives them)."""
    Figure = matplotlib_figure()  # noqa: N806 - a class
    grouped = panels(select(names, specs), frames, frozenset(_joints(names)), outputs)
    values = np.atleast_2d(values)
    t = values[:, list(names).index("t")]
    heights = [_panel_height(len(columns)) for columns in grouped.values()]
    fig = Figure(figsize=(9, 1.2 + sum(heights)), layout="constrained")
    axes = fig.subplots(len(grouped), 1, sharex=True, squeeze=False,
                        height_ratios=heights)[:, 0]
    for ax, ((name, unit, heading), columns) in zip(axes, grouped.items(), strict=True):
        for column in columns:
            ax.plot(t, values[:, list(names).index(column)], label=column)
        _decorate(ax, name, unit, heading, len(columns))
    axes[-1].set_xlabel("time t [s]")
    fig.suptitle(title or ", ".join(specs))
    return fig


def _legend_shape(lines: int) -> tuple[int, int]:
    """(columns, rows) of a legend: LEGEND_ROWS entries a column, up to LEGEND_COLUMNS
    columns, then longer columns."""
    columns = min(LEGEND_COLUMNS, 1 + (lines - 1) // LEGEND_ROWS)
    return columns, -(-lines // columns)


def _panel_height(lines: int) -> float:
    """[in] tall enough for the panel's legend beside it."""
    return max(PANEL_HEIGHT, 0.6 + 0.16 * _legend_shape(lines)[1])


def _decorate(ax, name: str, unit: str, heading: str, lines: int) -> None:
    ax.set_title(heading, fontsize="medium")
    ax.set_ylabel(f"{name} [{unit}]")
    ax.grid(True, alpha=0.3)
    if name in LOG_SCALE:
        _log_scale(ax)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False,
              fontsize="small" if lines <= LEGEND_ROWS else "x-small",
              ncol=_legend_shape(lines)[0])


def _log_scale(ax) -> None:
    """Logarithmic y axis whose floor is the round-off level (LOG_FLOOR), not an exact zero
    hit by a projection (which would squash the rest of the curve)."""
    data = np.concatenate([np.asarray(line.get_ydata(), float) for line in ax.get_lines()])
    positive = data[data > 0]
    if positive.size:
        ax.set_yscale("log")
        ax.set_ylim(bottom=max(positive.min(), min(LOG_FLOOR, positive.max())) / 2)


def check_output(path: Path) -> Path:
    """A usage error unless matplotlib can write this kind of file."""
    if Path(path).suffix.lower() not in SAVE_SUFFIXES:
        raise UsageError(f"cannot write '{path}': expected a file name ending in "
                         f"{', '.join(SAVE_SUFFIXES)}")
    return Path(path)


def save(fig, path: Path) -> Path:
    path = check_output(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    return path


def matplotlib_figure():
    try:
        from matplotlib.figure import Figure
    except ImportError:
        raise UsageError("casmech plot needs matplotlib, a dependency of casmech missing here; "
                         "install it with: pip install matplotlib") from None
    return Figure
