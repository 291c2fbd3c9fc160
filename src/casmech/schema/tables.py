"""Functions of time from data tables: CSV reading, splines, evaluation in CasADi.

A table is a CSV file with a header row naming its columns, one of them `t` (strictly
increasing). A column becomes a piecewise polynomial of t:

- `linear`: the broken line through the samples (C0; its second derivative is zero);
- `cubic` (default): the C2 cubic spline through the samples with NOT-A-KNOT end conditions
  (the third derivative is continuous at the second and the second-to-last sample, so four
  samples of any cubic reproduce it exactly); with `periodic: true`, PERIODIC end conditions
  instead (value, slope and curvature continuous across the wrap).

Outside [t_first, t_last]: with `periodic`, the table repeats with period t_last - t_first (its
first and last values must then be equal); without, t is clamped: the value holds the end
sample and the derivatives are zero there (error-free, but the speed jumps to zero at the end of
a table unless its end slope is zero).

Evaluation is a tree of `if_else` over the pieces in CasADi operations (SX, MX or DM), so AD gives
the exact derivatives of every order and code generation needs nothing special. The exact
antiderivative (speed motors driven by a table) is the same kind of function, of one degree more.
"""

from __future__ import annotations

import re
from dataclasses import replace
from functools import cached_property
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.errors import did_you_mean
from casmech.schema import files
from casmech.schema.resolved import ScalarFunction

MIN_ROWS = {"linear": 2, "cubic": 4}  # not-a-knot needs four samples; periodic cubic three
MIN_ROWS_PERIODIC = {"linear": 2, "cubic": 3}
MAX_ROWS = 20_000  # samples of a table (20 s at 1 kHz): each is a piece of the CasADi function
MAX_BYTES = files.MAX_TABLE_BYTES
PERIODIC_MATCH = 1e-9  # |y_last - y_first| allowed, relative to max |y| (and absolute for 0)
COLUMN = re.compile(r"[A-Za-z_][A-Za-z0-9_.]{0,63}\Z")  # a header cell shown in a hint


class TableError(Exception):
    """A problem with a table; `key` is the YAML key it belongs to (table, column, ...), `code`
    its diagnostic code (E300: a file or column that does not exist, E305: a path outside the
    model's folder or not a file, E306: too large, E103: bad contents). Messages never quote
    the file's contents beyond column names."""

    def __init__(self, key: str, message: str, hint: str | None = None, got: str | None = None,
                 code: str = "E103"):
        super().__init__(message)
        self.key, self.message, self.hint, self.got, self.code = key, message, hint, got, code


# ----------------------------------------------------------------------------------- reading
def _number_rows(lines: list[tuple[int, str]], width: int) -> np.ndarray:
    rows = []
    for line_number, line in lines:
        cells = [cell.strip() for cell in line.split(",")]
        try:
            values = [float(cell) for cell in cells]
        except ValueError:
            bad = next(k for k, cell in enumerate(cells) if not _is_number(cell))
            raise TableError("table", f"line {line_number} is not a row of numbers (value "
                             f"{bad + 1} of {len(cells)} is not a number)") from None
        if len(values) != width:
            raise TableError("table", f"line {line_number} has {len(values)} values, the header "
                             f"{width}") from None
        rows.append(values)
    return np.array(rows, float).reshape(len(rows), width)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _text(path: Path) -> str:
    """The file's text, read up to MAX_BYTES."""
    try:
        return files.read_bounded(path, MAX_BYTES).decode("utf-8")
    except files.TooLarge:
        raise TableError("table", f"table file '{path.name}' is larger than {MAX_BYTES >> 20} "
                         "MiB", code="E306", hint=f"at most {MAX_ROWS} rows are used; "
                         "resample the data") from None
    except FileNotFoundError:
        raise TableError("table", f"table file '{path}' not found", code="E300",
                         hint="the path is relative to the model file's folder") from None
    except UnicodeDecodeError:
        raise TableError("table", f"table file '{path.name}' is not UTF-8 text") from None
    except OSError as error:
        raise TableError("table", f"cannot read table file '{path.name}' "
                         f"({error.strerror or type(error).__name__})") from None


def read_columns(path: Path) -> dict[str, np.ndarray]:
    """Columns of a CSV file by header name (blank lines and lines starting with # skipped)."""
    lines = [(k + 1, line) for k, line in enumerate(_text(path).splitlines())
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise TableError("table", f"table file '{path.name}' is empty",
                         hint="write a header row (t, columns...) and one row per sample")
    if len(lines) - 1 > MAX_ROWS:
        raise TableError("table", f"table file '{path.name}' has {len(lines) - 1} rows, more "
                         f"than {MAX_ROWS}", code="E306", hint="resample the data")
    header = [name.strip() for name in lines[0][1].split(",")]
    values = _number_rows(lines[1:], len(header))
    return {name: values[:, k] for k, name in enumerate(header)}


def _columns_hint(name: str, columns) -> str:
    """'did you mean' or the header's names; only cells that look like column names are shown
    (a file that is not a table is not quoted)."""
    shown = [column for column in columns if COLUMN.match(column)]
    listed = f"columns: {', '.join(shown[:20])}" if shown else \
        "its first row is not a header of column names"
    return did_you_mean(name, shown) or listed


def samples(path: Path, column: str, interpolation: str, periodic: bool):
    """(t, y) of `column`, checked: t present, strictly increasing, finite, enough rows."""
    columns = read_columns(path)
    for name, key in (("t", "table"), (column, "column")):
        if name not in columns:
            raise TableError(key, f"no column '{name}' in '{path.name}'",
                             hint=_columns_hint(name, columns), code="E300")
    t, y = columns["t"], columns[column]
    needed = (MIN_ROWS_PERIODIC if periodic else MIN_ROWS)[interpolation]
    if len(t) < needed:
        raise TableError("table", f"a {interpolation} table needs at least {needed} rows",
                         got=f"{len(t)} rows")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise TableError("table", "the table holds a value that is not finite")
    steps = np.diff(t)
    if np.any(steps <= 0):
        k = int(np.argmax(steps <= 0))
        raise TableError("table", "column 't' must be strictly increasing",
                         got=f"t = {t[k]:g} then {t[k + 1]:g} (data rows {k + 1}, {k + 2})")
    if periodic and abs(y[-1] - y[0]) > PERIODIC_MATCH * max(1.0, float(np.max(np.abs(y)))):
        raise TableError("periodic", f"a periodic table must end where it starts: column "
                         f"'{column}' goes from {y[0]:g} to {y[-1]:g}",
                         hint="repeat the first row's value in the last row")
    return t, y


# ----------------------------------------------------------------------------------- splines
def _sparse_solve(size: int, entries: dict[tuple[int, int], float], rhs) -> np.ndarray:
    """Solve the sparse system {(row, column): value} x = rhs (CasADi's CSparse: the spline's
    matrix has three entries per row, so the work and memory grow with the rows, not their
    square)."""
    rows, columns = zip(*entries, strict=True)
    a = ca.DM.triplet(list(rows), list(columns), ca.DM(list(entries.values())), size, size)
    return np.array(ca.solve(a, ca.DM(rhs), "csparse")).ravel()


def _second_derivatives(t: np.ndarray, y: np.ndarray, periodic: bool) -> np.ndarray:
    """M_k = s''(t_k) of the cubic spline: not-a-knot, or periodic (sparse solve)."""
    n, h = len(t), np.diff(t)
    slope = np.diff(y) / h
    a: dict[tuple[int, int], float] = {}
    if periodic:  # unknowns M_0..M_{n-2}, M_{n-1} = M_0; the row of M_0 wraps around
        m = n - 1
        rhs = np.zeros(m)
        for i in range(m):
            before, after = h[i - 1], h[i]
            for column, value in (((i - 1) % m, before), (i, 2 * (before + after)),
                                  ((i + 1) % m, after)):
                a[(i, column)] = a.get((i, column), 0.0) + value
            rhs[i] = 6 * (slope[i] - slope[i - 1])
        second = _sparse_solve(m, a, rhs)
        return np.append(second, second[0])
    rhs = np.zeros(n)
    for i in range(1, n - 1):
        a.update({(i, i - 1): h[i - 1], (i, i): 2 * (h[i - 1] + h[i]), (i, i + 1): h[i]})
        rhs[i] = 6 * (slope[i] - slope[i - 1])
    # not-a-knot: the third derivative continuous at t_1 and at t_{n-2}
    a.update({(0, 0): h[1], (0, 1): -(h[0] + h[1]), (0, 2): h[0]})
    a.update({(n - 1, n - 3): h[-1], (n - 1, n - 2): -(h[-2] + h[-1]), (n - 1, n - 1): h[-2]})
    return _sparse_solve(n, a, rhs)


def spline_coefficients(t, y, interpolation: str, periodic: bool) -> np.ndarray:
    """(pieces, 4): ascending powers of s = t - t_k on each piece [t_k, t_k+1]."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    h, slope = np.diff(t), np.diff(y) / np.diff(t)
    if interpolation == "linear":
        zeros = np.zeros_like(h)
        return np.column_stack([y[:-1], slope, zeros, zeros])
    m = _second_derivatives(t, y, periodic)
    b = slope - h * (2 * m[:-1] + m[1:]) / 6
    return np.column_stack([y[:-1], b, m[:-1] / 2, (m[1:] - m[:-1]) / (6 * h)])


@record
class PiecewisePolynomial:
    """Pieces on `breaks` (ascending powers of t - t_k, any degree), extended outside the
    breaks linearly (`slopes` below/above; zero: clamped) or periodically, each period adding
    `increment` (the integral over one period, for an antiderivative)."""

    breaks: np.ndarray
    coefficients: np.ndarray  # (pieces, degree + 1)
    periodic: bool = False
    slopes: tuple[float, float] = (0.0, 0.0)
    increment: float = 0.0

    def _piece(self, k: int, u) -> Any:
        s, value = u - float(self.breaks[k]), 0.0
        for c in self.coefficients[k, ::-1]:  # Horner
            value = value * s + float(c)
        return value

    def _tree(self, u, low: int, high: int) -> Any:
        """The piece containing u among pieces low..high-1 (a balanced if_else tree)."""
        if high - low == 1:
            return self._piece(low, u)
        mid = (low + high) // 2
        return ca.if_else(u < float(self.breaks[mid]), self._tree(u, low, mid),
                          self._tree(u, mid, high))

    def casadi(self, t) -> Any:
        first, last = float(self.breaks[0]), float(self.breaks[-1])
        pieces = len(self.coefficients)
        if self.periodic:
            periods = ca.floor((t - first) / (last - first))
            return self._tree(t - periods * (last - first), 0, pieces) + periods * self.increment
        # if_else, not fmin/fmax: AD of fmax(t, first) at t = first gives half the slope
        before, after = t < first, t > last
        inside = self._tree(ca.if_else(before, first, ca.if_else(after, last, t)), 0, pieces)
        below, above = self.slopes
        return (inside + below * ca.if_else(before, t - first, 0)
                + above * ca.if_else(after, t - last, 0))

    @cached_property
    def numeric(self) -> ca.Function:
        """casadi.Function t -> value, for numerical evaluation (built once)."""
        t = ca.SX.sym("t")
        return ca.Function("table", [t], [self.casadi(t)])

    def antiderivative(self) -> PiecewisePolynomial:
        """The integral from breaks[0]: exact, one degree more, same extension rule."""
        pieces, degree = self.coefficients.shape
        h = np.diff(self.breaks)
        integrated = np.zeros((pieces, degree + 1))
        integrated[:, 1:] = self.coefficients / np.arange(1, degree + 1)
        piece_integrals = np.sum(integrated[:, 1:] * h[:, None] ** np.arange(1, degree + 1), axis=1)
        integrated[:, 0] = np.concatenate([[0.0], np.cumsum(piece_integrals)[:-1]])
        total = float(np.sum(piece_integrals))
        if self.periodic:
            return replace(self, coefficients=integrated, increment=total)
        ends = (float(self.coefficients[0, 0]), self._end_value())
        return replace(self, coefficients=integrated, slopes=ends)

    def _end_value(self) -> float:
        h = float(self.breaks[-1] - self.breaks[-2])
        return float(self.coefficients[-1] @ h ** np.arange(self.coefficients.shape[1]))


# ------------------------------------------------------------------------------ the function
@record
class TableExpr:
    """A table as an expression of t: the `Expr` interface (evaluate with the "numpy" or
    "casadi" backend, names, is_constant), so a table is an ordinary resolved.ScalarFunction
    wherever a function of time goes."""

    text: str
    polynomial: PiecewisePolynomial

    def evaluate(self, env, backend: str = "numpy") -> Any:
        t = env["t"]
        if backend == "casadi":
            return self.polynomial.casadi(t)
        times = np.asarray(t, float)
        mapped = self.polynomial.numeric.map(max(times.size, 1))(times.reshape(1, -1))
        return np.asarray(mapped).reshape(times.shape)

    def names_with_offsets(self) -> tuple[tuple[str, int, int], ...]:
        return (("t", 0, 0),)

    @property
    def symbols(self) -> frozenset[str]:
        return frozenset({"t"})

    @property
    def is_constant(self) -> bool:
        return False

    def __str__(self) -> str:
        return self.text


def table_function(path: Path, column: str, interpolation: str = "cubic", periodic: bool = False,
                   source: Any = None) -> ScalarFunction:
    """The function of t a table column describes (raises TableError)."""
    t, y = samples(path, column, interpolation, periodic)
    coefficients = spline_coefficients(t, y, interpolation, periodic and interpolation == "cubic")
    text = f"{interpolation}{' periodic' if periodic else ''} table {path.name}:{column}"
    expr = TableExpr(text, PiecewisePolynomial(t, coefficients, periodic))
    return ScalarFunction(text, expr, {}, ("t",), source)


def is_table(function: ScalarFunction) -> bool:
    return isinstance(function.expr, TableExpr)


def integral(function: ScalarFunction, start: float = 0.0) -> ScalarFunction:
    """The exact integral from t = start of a table function, as a function of t."""
    antiderivative = function.expr.polynomial.antiderivative()
    shifted = antiderivative.coefficients.copy()
    shifted[:, 0] -= float(antiderivative.numeric(start))
    text = f"integral from {start:g} to t of {function.text}"
    expr = TableExpr(text, replace(antiderivative, coefficients=shifted))
    return replace(function, text=text, expr=expr)
