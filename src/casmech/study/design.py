"""What a study runs: parameter values on a grid, sampled, or both (docs/sweeps.md).

A `Study` holds grid axes (name -> values), sampled parameters (name -> a distribution), the
sample count and seed, and the kept outputs (study/kept.py). `points()` lists the runs: the
Cartesian product of the grid axes, each combined with every sample when both are given.
Samples are drawn with NumPy's default generator from `seed`, one parameter after the other in
the order given, so a study is the same on every machine and with any number of workers.

The text forms are shared by the command line and the YAML `study:` block:
    grid     "0.8:1.2:5" (5 values from 0.8 to 1.2, ends included) or "100,200,400"
             (YAML: also a list of numbers)
    normal   "2,0.05" (mean, standard deviation >= 0)
    uniform  "0.1,0.3" (low <= high)
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import field

import numpy as np

from casmech.core.records import record

DISTRIBUTIONS = ("normal", "uniform")
MAX_RUNS = 10_000_000  # a study larger than this is a typo, not a plan


class StudyError(ValueError):
    """A malformed study value; the caller says where it was written. code: E103 for a value
    of the wrong form, E409 for one out of range (errors.CODES)."""

    def __init__(self, message: str, hint: str | None = None, code: str = "E103",
                 where: str | None = None):
        super().__init__(message)
        self.hint = hint
        self.code = code
        self.where = where  # the study's key at fault, when the caller cannot tell


def _number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise StudyError(f"'{text.strip()}' is not a number") from None
    if not math.isfinite(value):
        raise StudyError(f"'{text.strip()}' is not a finite number")
    return value


def grid_values(given: str | Sequence[float] | float) -> tuple[float, ...]:
    """A grid axis: 'start:stop:count', 'v1,v2,...', one number, or a list of numbers."""
    if isinstance(given, (int, float)) and not isinstance(given, bool):
        return (_number(str(given)),)
    if not isinstance(given, str):
        return tuple(_number(str(v)) for v in given) or _empty()
    parts = given.split(":")
    if len(parts) == 1:
        return tuple(_number(v) for v in given.split(",") if v.strip()) or _empty()
    if len(parts) != 3:
        raise StudyError(f"range '{given}' is not START:STOP:COUNT",
                         hint="e.g. 0.8:1.2:5 for 5 values from 0.8 to 1.2")
    start, stop = _number(parts[0]), _number(parts[1])
    try:
        count = int(parts[2])
    except ValueError:
        count = 0
    if count < 1 or str(count) != parts[2].strip():
        raise StudyError(f"range '{given}': COUNT must be a whole number >= 1",
                         hint="e.g. 0.8:1.2:5 for 5 values from 0.8 to 1.2", code="E409")
    if count > MAX_RUNS:  # refused before NumPy allocates the values
        raise StudyError(f"range '{given}': {count} values, more than a study's {MAX_RUNS} runs",
                         hint="a COUNT of at most a few thousand", code="E409")
    if count == 1 and start != stop:
        raise StudyError(f"range '{given}': one value cannot span {start:g} to {stop:g}",
                         hint="a COUNT of 2 or more, or a single number", code="E409")
    return tuple(float(v) for v in np.linspace(start, stop, count))


def _empty() -> tuple[float, ...]:
    raise StudyError("no values given", hint="e.g. 100,200,400 or 0.8:1.2:5")


def distribution(kind: str, given: str | Sequence[float]) -> tuple[str, float, float]:
    """('normal', mean, sigma) or ('uniform', low, high), checked."""
    values = ([_number(v) for v in given.split(",")] if isinstance(given, str)
              else [_number(str(v)) for v in given])
    if len(values) != 2:
        form = "MEAN,SIGMA" if kind == "normal" else "LOW,HIGH"
        raise StudyError(f"{kind} takes two numbers, {form}; got {len(values)}")
    a, b = values
    if kind == "normal" and b < 0:
        raise StudyError(f"normal: the standard deviation {b:g} is negative",
                         hint="write MEAN,SIGMA with SIGMA >= 0", code="E409")
    if kind == "uniform" and a > b:
        raise StudyError(f"uniform: low {a:g} is above high {b:g}", hint="write LOW,HIGH",
                         code="E409")
    return kind, a, b


@record
class Study:
    grid: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    distributions: Mapping[str, tuple[str, float, float]] = field(default_factory=dict)
    samples: int = 0
    seed: int = 0
    keep: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.samples < 0:
            raise StudyError(f"samples must be >= 0, got {self.samples}", code="E409")
        if self.seed < 0:
            raise StudyError(f"seed must be >= 0, got {self.seed}", code="E409")
        if self.distributions and not self.samples:
            raise StudyError("sampled parameters need a sample count",
                             hint="give samples: N (--samples N)", code="E409")
        if self.samples and not self.distributions:
            raise StudyError("samples given but no parameter to sample",
                             hint="name one with normal: or uniform: (--normal, --uniform)",
                             code="E409")
        both = set(self.grid) & set(self.distributions)
        if both:
            raise StudyError(f"'{sorted(both)[0]}' is both on the grid and sampled", code="E409")
        if not self.grid and not self.samples:
            raise StudyError("the study names no parameter",
                             hint="--grid NAME=VALUES, or --samples N with --normal/--uniform",
                             code="E409")
        if self.size() > MAX_RUNS:
            counts = " x ".join([*(str(len(v)) for v in self.grid.values()),
                                 *([str(self.samples)] if self.samples else [])])
            raise StudyError(f"the study has {self.size()} runs ({counts}), more than "
                             f"{MAX_RUNS}", hint="fewer values or samples", code="E409",
                             where="samples" if self.samples else "grid")

    @property
    def parameters(self) -> tuple[str, ...]:
        return (*self.grid, *self.distributions)

    def size(self) -> int:
        return math.prod(len(v) for v in self.grid.values()) * max(self.samples, 1)

    def points(self) -> list[dict[str, float]]:
        """The parameter values of every run, in run order."""
        grid = [dict(zip(self.grid, values, strict=True))
                for values in itertools.product(*self.grid.values())]
        if not self.samples:
            return grid
        rng = np.random.default_rng(self.seed)
        drawn = {name: (rng.normal(a, b, self.samples) if kind == "normal"
                        else rng.uniform(a, b, self.samples)).tolist()
                 for name, (kind, a, b) in self.distributions.items()}
        samples = [{name: values[k] for name, values in drawn.items()}
                   for k in range(self.samples)]
        return [{**g, **s} for g in grid for s in samples]

    def describe(self) -> dict:
        """JSON-ready, as metadata.json records it."""
        return {"grid": {k: list(v) for k, v in self.grid.items()},
                "distributions": {k: {"kind": kind, ("mean" if kind == "normal" else "low"): a,
                                      ("sigma" if kind == "normal" else "high"): b}
                                  for k, (kind, a, b) in self.distributions.items()},
                "samples": self.samples, "seed": self.seed, "keep": list(self.keep),
                "runs": self.size()}
