"""Kept outputs of a study run: one number per run from its results table (docs/sweeps.md).

    COLUMN@T        the column at time T (linear interpolation between output rows)
    max(COLUMN)     min(COLUMN)     final(COLUMN)
    integral(COLUMN)   trapezoid rule over the output rows (accurate to O(output_step^2))
    crossing(COLUMN)   the first time after the first row at which the column changes sign,
                       by linear interpolation between the two rows around it (NaN if never);
                       for a sinusoid of angular frequency w sampled every h, off by at most
                       w^2 h^3 / (36 sqrt 3) (the root of a cubic's interpolation error)
    event(NAME)        the time of the first event NAME of the model's `events:` (located to
                       the run's tolerance, runtime.events; NaN if it never happened)

COLUMN is a name of the results contract (runtime.results.column_names). A kept output's
column in sweep.csv is its text as written (`max(bar.z)`). A run with no rows keeps NaN.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np

from casmech.core.records import record
from casmech.errors import did_you_mean
from casmech.study.design import StudyError


def _at(t: np.ndarray, v: np.ndarray, when: float) -> float:
    return float(np.interp(when, t, v)) if t[0] <= when <= t[-1] else float("nan")


def _crossing(t: np.ndarray, v: np.ndarray, _when) -> float:
    before, after = v[:-1], v[1:]
    changes = np.flatnonzero((before * after < 0) | ((after == 0) & (before != 0)))
    if not len(changes):
        return float("nan")
    i = changes[0]
    return float(t[i] - v[i] * (t[i + 1] - t[i]) / (v[i + 1] - v[i]))


def _integral(t: np.ndarray, v: np.ndarray, _when) -> float:
    return float(np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(t)))


# reduction name -> f(times, column values, time of @ or None) for a table of >= 1 row
REDUCTIONS = {
    "max": lambda t, v, _: float(np.max(v)),
    "min": lambda t, v, _: float(np.min(v)),
    "final": lambda t, v, _: float(v[-1]),
    "integral": _integral,
    "crossing": _crossing,
    "at": _at,
}
_CALL = re.compile(r"^\s*(\w+)\s*\(\s*(.+?)\s*\)\s*$")


@record
class Kept:
    text: str  # as written: the column name in sweep.csv
    reduction: str
    column: str
    when: float | None = None

    def value(self, names: Sequence[str], values: np.ndarray, events=()) -> float:
        if self.reduction == "event":
            return next((float(e.t) for e in events if e.name == self.column), float("nan"))
        if not len(values):
            return float("nan")
        index = list(names).index
        t, v = values[:, index("t")], values[:, index(self.column)]
        return REDUCTIONS[self.reduction](t, v, self.when)


def parse(text: str) -> Kept:
    """One kept output's text (a StudyError when it has none of the forms)."""
    call = _CALL.match(text)
    if call:
        reduction, column = call.groups()
        if reduction == "event":
            return Kept(text, reduction, column)
        if reduction not in REDUCTIONS or reduction == "at":
            forms = ", ".join(f"{name}(COLUMN)" for name in REDUCTIONS if name != "at")
            raise StudyError(f"unknown kept output '{reduction}(...)'",
                             hint=did_you_mean(reduction, [*REDUCTIONS, "event"])
                             or f"one of {forms}, event(NAME), COLUMN@T")
        return Kept(text, reduction, column)
    column, sep, when = text.rpartition("@")
    if not sep or not column.strip():
        raise StudyError(f"kept output '{text}' is not COLUMN@T or max/min/final/integral/"
                         "crossing(COLUMN)")
    try:
        time = float(when)
    except ValueError:
        raise StudyError(f"kept output '{text}': '{when}' is not a time") from None
    return Kept(text, "at", column.strip(), time)


def check(kept: Kept, names: Sequence[str], t_end: float, events: Sequence[str] = ()) -> None:
    """The column (or the event) exists and the time of @ is within the run."""
    if kept.reduction == "event":
        if kept.column not in events:
            raise StudyError(f"kept output '{kept.text}': the model has no event "
                             f"'{kept.column}'",
                             hint=did_you_mean(kept.column, events) or (
                                 f"its events: {', '.join(events)}" if events else
                                 "declare it in the model's events: block"))
        return
    if kept.column not in names:
        raise StudyError(f"kept output '{kept.text}': no results column '{kept.column}'",
                         hint=did_you_mean(kept.column, names))
    if kept.when is not None and not 0.0 <= kept.when <= t_end:
        raise StudyError(f"kept output '{kept.text}': time {kept.when:g} is outside the run "
                         f"[0, {t_end:g}]")


def values(kept: Sequence[Kept], names: Sequence[str], table: np.ndarray,
           events=()) -> dict[str, float]:
    """Every kept output of a run (events: its runtime.events records)."""
    return {k.text: k.value(names, table, events) for k in kept}
