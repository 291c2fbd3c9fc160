"""Events of a dynamics run: where a scalar of the state crosses zero, located to the run's
tolerance (docs/analyses.md#events).

An Event is a casadi.Function of one results row's state (t, q, q_dot, q_ddot, lam: r-p
coordinates, as Result.extend takes them) to a scalar, with a direction (rising, falling, both)
and an action (stop, log). The model's `events:` block becomes such Functions here
(model_events); other code (contact onset, joint limits) may declare its own.

A Watch sees every block of rows a run integrates: the events' values on the block are one
mapped call; in an output interval where an event's value changes sign in its direction, the
crossing is located by the Illinois method (regula falsi that halves the retained end's value),
each of its values by integrating again from the interval's start to the trial time with the
run's own integrator and tolerances (`probe`), until the bracket is rtol |t| wide (at least a
few ulps; the trial values carry the integration error, so a narrower bracket only costs
trials). The time found is exact to the integration error of the run, not to the output grid
(docs/decisions/events.md has the measurements behind this choice). A sign change inside
one output interval that returns before its end (two crossings) is not seen.

Recorded: Result.events (EventRecord, in time order) and Result.event_states (a Result holding
each event's row). `stop` ends the run at the event: the rows before it, then the event's row
last, status "stopped by event" (raises Stopped for the run to end its loop).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import casadi as ca
import numpy as np

from casmech.core.options import DynamicsSolver
from casmech.core.records import record
from casmech.equations import readings
from casmech.equations.functions import SystemFunctions
from casmech.equations.symbols import Coordinates
from casmech.errors import AnalysisError, FailureContext, solver_reason
from casmech.runtime import cancel
from casmech.runtime.buffers import ColumnCall
from casmech.runtime.results import Result
from casmech.runtime.workspace import Workspace, of

DIRECTIONS = {"rising": (1,), "falling": (-1,), "both": (1, -1)}
SIGNS = {1: "rising", -1: "falling"}
ACTIONS = ("stop", "log")
STOPPED = "stopped by event"  # Result.status of a run a stop event ended
ULPS = 64  # the narrowest bracket location stops at, in units of eps * |t| (a roundoff floor)
ITERATIONS = DynamicsSolver().event_iterations  # Illinois steps per crossing, by default


@record
class Event:
    """A zero crossing to watch: `function` (t, q, q_dot, q_ddot, lam) -> scalar."""

    name: str
    function: ca.Function
    direction: str = "both"
    action: str = "log"

    def __post_init__(self):
        if self.direction not in DIRECTIONS or self.action not in ACTIONS:
            raise ValueError(f"event '{self.name}': direction {self.direction!r} / action "
                             f"{self.action!r} not in {tuple(DIRECTIONS)} / {ACTIONS}")


@record
class EventRecord:
    """An event that happened: its name, time, the crossing's sign and the action taken."""

    name: str
    t: float
    direction: str  # rising | falling
    action: str


class Stopped(Exception):
    """A stop event ended the run; its rows are recorded."""


# ------------------------------------------------------------------ the model's `events:`
def state_values(functions: SystemFunctions, x: Coordinates, names) -> dict[str, Any]:
    """The state names an event reads (schema.events.state_names, the contacts' and stops'
    columns and the outputs that read no reactions) as expressions of x
    (equations.readings)."""
    found = readings.Readings(functions.ir, x)
    return {name: found[name] for name in names}


def event_function(functions: SystemFunctions, when) -> ca.Function:
    """(t, q, q_dot, q_ddot, lam) -> the value of a resolved `when` (an SX function, the
    same whether the system's functions are interpreted or compiled)."""
    x = Coordinates.create(functions.n_bodies)
    lam = ca.SX.sym("lam", functions.n_rows)
    states = state_values(functions, x, [n for n in when.variables if n != "t"])
    value = x.ground_fixed(ca.SX(when.casadi(t=x.t, **states)))
    return ca.Function("event", [x.t, x.q, x.q_dot, x.q_ddot, lam], [value])


def model_events(functions: SystemFunctions,
                 workspace: Workspace | None = None) -> tuple[Event, ...]:
    """The model's `events:` as Events (built once per workspace)."""
    return of(functions, workspace).one("events", lambda: tuple(
        Event(e.name, event_function(functions, e.when), e.direction, e.action)
        for e in functions.ir.analysis.events))


# ----------------------------------------------------------------------------- location
def illinois(g: Callable[[float], float], a: float, b: float, ga: float, gb: float,
             xtol: float, iterations: int = ITERATIONS) -> float:
    """A zero of g in [a, b] (ga, gb of opposite signs or one of them 0) by the Illinois
    method, to a bracket `xtol` wide or after `iterations` steps; the last trial point (whose
    value g computed)."""
    if gb == 0:
        return b
    c, side = b, 0
    for _ in range(iterations):
        if b - a <= xtol:
            break
        c = (a * gb - b * ga) / (gb - ga)
        if not a < c < b:  # rounding at a nearly flat end: bisect
            c = 0.5 * (a + b)
        gc = g(c)
        if gc == 0 or not np.isfinite(gc):
            return c
        if np.sign(gc) == np.sign(gb):
            b, gb = c, gc
            if side == -1:
                ga *= 0.5
            side = -1
        else:
            a, ga = c, gc
            if side == 1:
                gb *= 0.5
            side = 1
    return c


def stacked(functions: Sequence[ca.Function]) -> ca.Function:
    """One Function of the events' common inputs giving all their values (a column); SX
    when every event's function is."""
    if len(functions) == 1:
        return functions[0]
    sx = all(f.is_a("SXFunction") for f in functions)
    args = functions[0].sx_in() if sx else functions[0].mx_in()
    return ca.Function("events", args, [ca.vertcat(*(f(*args) for f in functions))])


Rows = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]  # q, q_dot, q_ddot, lam: k x n
# probe(t_start, state at t_start, t, t_end) -> (the row at t (1 x n each), the state at t):
# t_start < t < t_end, the rows before and after the crossing
Probe = Callable[[float, Any, float, float], tuple[Rows, Any]]


class Watch:
    """Finds, locates and records the events of one run (see the module docstring)."""

    def __init__(self, events: Sequence[Event], result: Result, rtol: float = 0.0,
                 iterations: int = ITERATIONS):
        self.events, self.result, self.rtol = tuple(events), result, rtol
        self.iterations = iterations
        self.values = stacked([e.function for e in events])
        self.values_at = ColumnCall(self.values)
        self.last: np.ndarray | None = None  # the events' values at the last row
        self.probes = 0
        result.events, result.event_states = [], Result("events")
        result.metadata["event_probes"] = 0

    def evaluate(self, times, rows: Rows) -> np.ndarray:
        """The events' values at every row (n_events x k), by mapped calls in blocks."""
        times = np.asarray(times, float)
        (out,) = self.values_at(times[None, :], *(np.asarray(r).T for r in rows))
        return out.reshape(len(self.events), len(times))

    def start(self, t0: float, rows: Rows) -> None:
        """The first row of the run: values to compare the next rows with."""
        self.last = self.evaluate([t0], rows)[:, 0]

    def record(self, t_start: float, start, times, state_at: Callable[[int], Any],
               rows: Rows, probe: Probe) -> None:
        """Append a block of rows to the result with the events crossed in it (`start`: the
        state at t_start, the row before the block; state_at(j): the state at times[j]).
        Raises Stopped after recording the rows up to a stop event and the event's row."""
        times = np.asarray(times, float)
        values = self.evaluate(times, rows)
        before = np.column_stack([self.last, values[:, :-1]])
        crossings, done = self._crossings(before, values), 0
        for j in sorted(set(crossings[0].tolist())):
            self._append(times, rows, done, j)  # the rows before the crossing come first
            done = j
            a = times[j - 1] if j else t_start
            state = state_at(j - 1) if j else start
            at_b = tuple(r[j:j + 1] for r in rows)
            found = sorted((self._locate(i, (a, state, before[i, j]), (times[j], at_b,
                                                                       values[i, j]), probe)
                            for i in crossings[1][crossings[0] == j]), key=lambda hit: hit[0].t)
            stop = next((hit for hit in found if hit[0].action == "stop"), None)
            for hit in found[:found.index(stop) + 1] if stop else found:
                self._keep(*hit)
            if stop is not None:
                self.result.extend([stop[0].t], *stop[1])
                self.result.status = STOPPED
                raise Stopped(stop[0].name)
        self._append(times, rows, done, len(times))
        self.last = values[:, -1]

    def _crossings(self, before: np.ndarray, after: np.ndarray):
        """(columns, events) of every sign change in an event's direction, by column."""
        rising = (before < 0) & (after >= 0)
        falling = (before > 0) & (after <= 0)
        wanted = np.array([[1 in DIRECTIONS[e.direction], -1 in DIRECTIONS[e.direction]]
                           for e in self.events], bool)
        hits = (rising & wanted[:, :1]) | (falling & wanted[:, 1:])
        events, columns = np.nonzero(hits)
        order = np.lexsort((events, columns))
        return columns[order], events[order]

    def _locate(self, i: int, start, end, probe: Probe):
        """(EventRecord, its row) of event i's crossing between start = (a, the state at a,
        the value at a) and end = (b, the row at b, the value at b)."""
        (a, state, ga), (b, row_b, gb) = start, end
        event, trials = self.events[i], {b: row_b}

        def row_at(t: float) -> Rows:
            self.probes += 1
            self.result.metadata["event_probes"] = self.probes
            try:
                return probe(a, state, t, b)[0]
            except RuntimeError as error:  # the integrator failed on the way to t
                cancel.check(error)
                cause = (f"locating event '{event.name}' between t = {a:.6g} and {b:.6g}: the "
                         f"integrator failed before t = {t:.10g} ({solver_reason(error)})")
                raise AnalysisError(FailureContext(a, cause, [], "")) from None

        def value(t: float) -> float:
            trials[t] = row_at(t)
            return float(self.evaluate([t], trials[t])[i, 0])

        xtol = max(ULPS * np.finfo(float).eps, self.rtol) * max(abs(a), abs(b), b - a)
        t = illinois(value, a, b, ga, gb, xtol, self.iterations)
        row = trials[t] if t in trials else row_at(t)
        return EventRecord(event.name, float(t), SIGNS[1 if gb > ga else -1], event.action), row

    def _keep(self, record: EventRecord, row: Rows) -> None:
        self.result.events.append(record)
        self.result.event_states.extend([record.t], *row)

    def _append(self, times, rows: Rows, first: int, end: int) -> None:
        if end > first:
            self.result.extend(times[first:end], *(r[first:end] for r in rows))


def watch(functions: SystemFunctions, result: Result, extra: Sequence[Event] = (),
          rtol: float = 0.0, iterations: int = ITERATIONS,
          workspace: Workspace | None = None,
          model: tuple[Event, ...] | None = None) -> Watch | None:
    """The Watch of a run over the model's events (`model`, where the caller holds them:
    model_events') and `extra` ones, locating to the run's rtol; None without any (the run
    then does no event work at all)."""
    events = (*(model_events(functions, workspace) if model is None else model), *extra)
    return Watch(events, result, rtol, iterations) if events else None


def has_stop(watcher: Watch | None) -> bool:
    return watcher is not None and any(e.action == "stop" for e in watcher.events)


# -------------------------------------------------------------------------------- output
