"""Results of an analysis and their table per the results contract (docs/format.md)."""

from __future__ import annotations

import copy
from collections.abc import Callable, Mapping

import casadi as ca
import numpy as np

from casmech.core.columns import BODY_COLUMNS, JOINT_COLUMNS
from casmech.equations import contact, readings
from casmech.equations.functions import SystemFunctions
from casmech.runtime import reaction_frames as reaction_frames_of
from casmech.runtime.nonfinite import NonFinite, check_states
from casmech.runtime.row_calls import over_rows, rows_of
from casmech.runtime.workspace import Workspace, of

STATES = ("q", "q_dot", "q_ddot", "lam")


class Result:
    """States at the output times; q_ddot and lam complete the state where known.

    Rows arrive one at a time (append) or as blocks (extend); `times` reads as a list of
    floats, q, q_dot, q_ddot and lam as 2-D arrays (rows x n). on_row, when given, is called
    with the time of every row as it is added (progress); when it has a `rows_added`
    attribute, that is called with the Result after each block is added, before the times
    (output.streaming writes the rows as they come)."""

    def __init__(self, analysis: str, metadata: dict | None = None,
                 on_row: Callable[[float], None] | None = None):
        self.analysis = analysis
        self.metadata = {} if metadata is None else metadata
        self.on_row = on_row
        # further files of the analysis: name in the output folder -> writer(path) (modal)
        self.files: dict[str, Callable] = {}
        self.linear_model = None  # modal: runtime.modal.LinearModel
        # dynamics with events (runtime.events): the EventRecords in time order, and a Result
        # holding each one's row (None: the run watched no events)
        self.events: list = []
        self.event_states: Result | None = None
        # results columns a run computed beyond the bundle's (a stuck joint's friction:
        # runtime.friction): name -> a value per row
        self.fixed_columns: dict[str, np.ndarray] = {}
        self._blocks: dict[str, list[np.ndarray]] = {"t": [], "q": [], "q_dot": [],
                                                     "q_ddot": [], "lam": []}  # ("t", *STATES)

    def append(self, t, q, q_dot, q_ddot, lam) -> None:
        """One row: t a float, the states 1-D."""
        self.extend([t], *(np.reshape(np.asarray(v, float), (1, -1))
                           for v in (q, q_dot, q_ddot, lam)))

    def extend(self, times, q, q_dot, q_ddot, lam, checked: bool = False) -> None:
        """A block of rows: times (k,), the states 2-D arrays (k x n), row j at times[j]. A row
        whose states are not all finite is refused: the rows before it are added, then
        runtime.nonfinite.NonFinite is raised. `checked`: rows their maker found finite (a
        run's kept row at t0: runtime.joint_recorder), not checked again."""
        times = np.asarray(times, float).reshape(-1)
        arrays = [np.asarray(q, float), np.asarray(q_dot, float), np.asarray(q_ddot, float),
                  np.asarray(lam, float)]
        count = len(times)
        for k, value in enumerate(arrays):
            if value.ndim != 2 or len(value) != count:
                raise ValueError(f"{STATES[k]}: expected {count} rows, got shape {value.shape}")
        bad = None if checked else check_states(times, *arrays)
        values = dict(zip(STATES, arrays, strict=True))
        if bad is not None:
            if bad:
                self._add(times[:bad], {name: value[:bad] for name, value in values.items()})
            name = next((name for name, value in values.items()
                         if not np.isfinite(value[bad]).all()), "t")
            raise NonFinite(float(times[bad]), name, values[name][bad] if name != "t" else
                            times[bad:bad + 1], (values["q"][bad], values["q_dot"][bad]), self)
        self._add(times, values)

    def _add(self, times: np.ndarray, values: dict) -> None:
        self._blocks["t"].append(times)
        for name, value in values.items():
            self._blocks[name].append(value)
        if self.on_row is not None:
            added = getattr(self.on_row, "rows_added", None)
            if added is not None:  # a sink of the rows (output.streaming)
                added(self, times, *values.values())
            for t in times.tolist():
                self.on_row(t)

    @classmethod
    def of_rows(cls, times, q, q_dot, q_ddot, lam, analysis: str = "rows") -> Result:
        """A Result holding these rows as they are (no checks, no callbacks)."""
        result = cls(analysis)
        for name, value in zip(("t", *STATES), (times, q, q_dot, q_ddot, lam), strict=True):
            result._blocks[name].append(np.asarray(value, float))
        return result

    def with_lam(self, lam) -> Result:
        """A copy with the same rows and the multipliers `lam` (rows x m), its own
        fixed_columns; the rest (metadata, events, callbacks) shared."""
        copied = copy.copy(self)
        copied._blocks = {name: [self._array(name)] for name in ("t", *STATES)}
        copied._blocks["lam"] = [np.asarray(lam, float)]
        copied.fixed_columns = dict(self.fixed_columns)
        return copied

    def _array(self, name: str) -> np.ndarray:
        blocks = self._blocks[name]
        if len(blocks) > 1:  # consolidate once, so repeated reads are free
            blocks[:] = [np.concatenate(blocks)]
        return blocks[0] if blocks else np.zeros((0,) if name == "t" else (0, 0))

    @property
    def times(self) -> list[float]:
        return self._array("t").tolist()

    @property
    def t(self) -> np.ndarray:
        """The output times as one array (times reads them as a list)."""
        return self._array("t")

    @property
    def q(self) -> np.ndarray:
        return self._array("q")

    @property
    def q_dot(self) -> np.ndarray:
        return self._array("q_dot")

    @property
    def q_ddot(self) -> np.ndarray:
        return self._array("q_ddot")

    @property
    def lam(self) -> np.ndarray:
        return self._array("lam")

    def __len__(self) -> int:
        return sum(len(block) for block in self._blocks["t"])

    # the SystemFunctions that computed the rows (casmech.analyze sets it): the source of the
    # results table, the DataFrame and the summary's model name and column count
    functions: SystemFunctions | None = None
    status = "complete"  # or "failed" / "interrupted": the rows kept by an AnalysisError;
    # "stopped by event": a stop event ended a dynamics run (runtime.events)

    def to_dataframe(self):
        """The results table as a pandas DataFrame, as casmech.load_results reads it from the
        files of a run: index t, the contract's columns, attrs["units"], attrs["metadata"]."""
        from casmech.runtime import frames

        if self.functions is None:
            raise ValueError("this Result has no system functions to tabulate its rows with; "
                             "use casmech.analyze's Result, or casmech.results_table(functions, "
                             "result)")
        names, values = table(self.functions, self)
        ir = self.functions.ir
        chosen = reaction_frames_of.describe(ir, reaction_frames_of.chosen(ir),
                                             self.functions.body_names)
        return frames.frame(names, values, {**self.metadata, "reaction_frames": chosen})

    def events_dataframe(self):
        """The events (runtime.events) as a pandas DataFrame, as events.csv holds them:
        columns t, name, then every results column at the event (no rows without events)."""
        import pandas as pd

        if self.functions is None:
            raise ValueError("this Result has no system functions to tabulate its events with")
        names, rows = events_table(self.functions, self)
        return pd.DataFrame(rows, columns=names)

    def _facts(self) -> dict[str, str]:
        from casmech.runtime import frames

        known = self.functions is not None
        extra = {key: self.metadata[key] for key in ("formulation", "mode")
                 if key in self.metadata}
        return frames.summary(self.functions.ir.name if known else "?", self.analysis,
                              self.times, self.status,
                              len(column_names(self.functions)) if known else 0, extra)

    def __repr__(self) -> str:
        from casmech.runtime import frames

        return frames.summary_text(self._facts())

    def _repr_html_(self) -> str:
        from casmech.runtime import frames

        return frames.summary_html(self._facts())


def column_names(functions: SystemFunctions) -> list[str]:
    """The results contract's columns, then the joint states and the outputs
    (equations/readings.py); named once per bundle (its workspace)."""
    return list(of(functions, None).one("column_names", lambda: tuple(_names(functions))))


def _names(functions: SystemFunctions) -> list[str]:
    names = ["t"]
    names += [f"{b}.{c}" for b in functions.body_names for c in BODY_COLUMNS]
    names += [f"{j.name}.{c}" for j in functions.joints for c in JOINT_COLUMNS]
    return names + ["energy", "constraint_violation", *contact.output_names(functions.ir),
                    *readings.names(functions.ir)]


def readings_function(functions: SystemFunctions,
                      workspace: Workspace | None = None) -> ca.Function:
    """equations.readings.columns_function of the bundle's IR, built once per workspace."""
    return of(functions, workspace).one("readings",
                                        lambda: readings.columns_function(functions.ir))


def row(functions: SystemFunctions, t, q, q_dot, q_ddot, lam) -> np.ndarray:
    """One row of the results table, numerically (row_function does the same symbolically)."""
    nb = functions.n_bodies
    omega, alpha = functions.evaluate("body_rates", q, q_dot, q_ddot)
    per_body = [
        np.concatenate([q[3 * k:3 * k + 3], q[3 * nb + 4 * k:3 * nb + 4 * k + 4],
                        q_dot[3 * k:3 * k + 3], omega[:, k], q_ddot[3 * k:3 * k + 3], alpha[:, k]])
        for k in range(nb)
    ]
    force, torque = functions.evaluate("reactions", t, q, q_dot, lam)
    per_joint = [np.concatenate([force[:, j], torque[:, j]]) for j in range(len(functions.joints))]
    kinetic, potential = functions.evaluate("energy", t, q, q_dot)
    violation = np.max(np.abs(functions.vector("phi", t, q)), initial=0.0)
    elements = functions.vector("element_outputs", t, q, q_dot)  # contacts and stops
    derived = np.array(readings_function(functions)(t, q, q_dot, q_ddot, force, torque)).ravel()
    return np.concatenate([[t], *per_body, *per_joint, [(kinetic + potential).item(), violation],
                           elements, derived])


def row_function(functions: SystemFunctions) -> ca.Function:
    """(t, q, q_dot, q_ddot, lam) -> the results row (a column), as `row` computes it:
    equations.results_row.row_function over the bundle's terms and its readings_function."""
    from casmech.equations import results_row

    return results_row.row_function(functions, readings_function(functions))


def row_call(functions: SystemFunctions) -> ca.Function:
    """The results row `table` maps over the rows: a compiled bundle's compiled with it
    (backends.results_row: the same graph over the same functions, loaded from the cache),
    else row_function."""
    if functions.library_key is not None:
        from casmech.backends import results_row as compiled_row

        compiled = compiled_row.compiled(functions)
        if compiled is not None:
            return compiled
    return row_function(functions)


def table(functions: SystemFunctions, result: Result,
          reaction_frames: str | Mapping[str, str] | None = None,
          workspace: Workspace | None = None) -> tuple[list[str], np.ndarray]:
    """Every row at once: row_call (made once per workspace, by default the bundle's) over
    the rows (runtime.row_calls: a compiled row in one C loop, else casadi's map writing into
    NumPy memory); then each joint's reaction columns
    in its frame: the model's `reactions: {frame: ...}`, replaced by `reaction_frames` for
    every joint (a frame name) or the joints it names (a mapping)."""
    frames = reaction_frames_of.chosen(functions.ir, reaction_frames)
    names = column_names(functions)
    rows = len(result)
    if rows == 0:
        return names, np.zeros((0, len(names)))
    space = of(functions, workspace)
    with space.lock:  # the row's call (its work vectors) serves one thread at a time
        call = space.one("results_row", lambda: over_rows(row_call(functions)))
        (values,) = rows_of(call, np.asarray(result.times, float), result.q, result.q_dot,
                            result.q_ddot, result.lam)
    start = 1 + len(BODY_COLUMNS) * functions.n_bodies
    block = slice(start, start + len(JOINT_COLUMNS) * len(functions.joints))
    values[:, block] = reaction_frames_of.written(functions.ir, frames, result.q,
                                                  values[:, block])
    return names, with_fixed(result, names, values)


def with_fixed(result: Result | None, names: list[str], values: np.ndarray,
               first: int = 0) -> np.ndarray:
    """`values` (rows first .. of `result`) with the columns the run computed itself
    (Result.fixed_columns) where it holds those rows."""
    for name, column in getattr(result, "fixed_columns", {}).items():
        if name in names and len(column) >= first + len(values):
            values[:, names.index(name)] = column[first:first + len(values)]
    return values


def events_table(functions: SystemFunctions, result: Result, reaction_frames=None,
                 workspace: Workspace | None = None) -> tuple[list[str], list[list]]:
    """(names, rows) of events.csv: t, name, then every results column at the event (the
    reaction columns in the frames `table` writes them in)."""
    names = ["t", "name", *column_names(functions)[1:]]
    if not result.events:
        return names, []
    _, values = table(functions, result.event_states, reaction_frames, workspace)
    return names, [[record.t, record.name, *row[1:].tolist()]
                   for record, row in zip(result.events, values, strict=True)]
