"""The one driver of a dynamics run over its output grid, for every formulation: the r-p and
r-omega DAEs on IDAS and their projected Runge-Kutta fallback (runtime.dynamics), and joint
coordinates on CVODES or IDAS (runtime.joint_dynamics).

A formulation gives `drive` its step: step(t0, times, state) -> Block, one solver call from
(t0, state) over a chunk of the grid, whose Block holds a leading part of those times (all of
them, unless the step stopped early: a projection, a failure it handles itself) with their
results rows. The driver

- cuts the grid into chunks (Chunks: a first size, doubling from call to call or not, a limit
  a failure may set);
- polls the run's cancellation token before every solver call (runtime.cancel; inside a call a
  signal stops the solver at once), so a cancelled run ends with the rows recorded so far, and
  a run whose rows are all computed is complete;
- with `halves`, does a chunk a solver fails on (a RuntimeError) again in halves, so the rows
  before the failure are kept and `fail` names the output interval it happened in;
- records each block in the Result (whose on_row is the progress callback), or through the
  events' Watch (an event's trial points integrate from the row before them by the block's
  `probe`), and ends the run at a stop event;
- records the rows a solver call had computed when a signal stopped it (the step attaches
  them to the errors.Interrupted as `block`: `completed` counts an interrupted integrator's
  finished grid points), then lets the Interrupted go on.

Chunk sizes are counted in output intervals, never in wall time: the integrator restarts
between calls, so where a chunk ends changes the results (at the integration error), and a
run's results must not depend on how fast the machine ran it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from casmech.core.records import record
from casmech.errors import AnalysisError, Interrupted
from casmech.runtime import cancel, events
from casmech.runtime.results import Result


@record(frozen=False)
class Block:
    """What one step integrated: `times` (a leading part of the times asked), their results
    `rows` (q, q_dot, q_ddot, lam: one row per time), the state to continue from
    (`next_state`, at times[-1]), `start` (the state at t0 as `probe` takes it) and
    `state_at(j)` (at times[j]) for the events, `probe(t_start, state, t, t_end) -> (rows,
    state)`, one trial point, and whether the step ended early at a restart (`restarted`)."""

    times: np.ndarray
    rows: tuple
    next_state: Any
    start: Any = None
    state_at: Callable[[int], Any] | None = None
    probe: Callable | None = None
    restarted: bool = False


class Chunks:
    """Output intervals per solver call: `first`, then `size` (or, growing, twice the last,
    or twice what a restarted call used), at most `limit` once a failure set one."""

    def __init__(self, size: int, first: int | None = None, grow: bool = False):
        self.size, self.base, self.grow, self.limit = first or size, size, grow, None

    def done(self, used: int, restarted: bool) -> None:
        if self.grow:
            self.size = 2 * used if restarted else 2 * self.size
        if self.limit is not None:
            self.size = min(self.size, self.limit)

    def cap(self, limit: int) -> None:
        """After a failure: no chunk longer than `limit` from here on."""
        self.limit = self.size = limit


def drive(result: Result, times: np.ndarray, state, step: Callable[..., Block],
          chunks: Chunks, watch: events.Watch | None = None, halves: bool = False,
          fail: Callable[[float, float, RuntimeError], AnalysisError] | None = None) -> None:
    """Integrate over `times` from (times[0], state) by `step`, recording every block (the
    row at times[0] is the caller's); returns at the end of the grid or at a stop event."""
    k = 0
    try:
        while k < len(times) - 1:
            chunk = times[k + 1:k + 1 + chunks.size]
            used, restarted, state = _advance(result, times[k], chunk, state, step, watch,
                                              halves, fail)
            k += used
            chunks.done(used, restarted)
    except events.Stopped:
        return


def _advance(result: Result, t0: float, times: np.ndarray, state, step, watch, halves, fail):
    """(times recorded, whether the last block restarted, the state at the last time): one
    block, or on a failure with `halves` the same in two halves."""
    cancel.poll()
    try:
        block = step(t0, times, state)
    except Interrupted as interrupted:
        part = getattr(interrupted, "block", None)
        if part is not None and len(part.times):
            _record(result, t0, part, watch)
        raise
    except RuntimeError as error:
        cancel.check(error)  # a signal is not a solver failure
        if not halves:
            raise
        if len(times) == 1:
            raise fail(t0, times[0], error) from None
        half = len(times) // 2
        first, _, state = _advance(result, t0, times[:half], state, step, watch, halves, fail)
        second, restarted, state = _advance(result, times[half - 1], times[half:], state, step,
                                            watch, halves, fail)
        return first + second, restarted, state
    _record(result, t0, block, watch)
    return len(block.times), block.restarted, block.next_state


def _record(result: Result, t0: float, block: Block, watch) -> None:
    if watch is None:
        result.extend(block.times, *block.rows)
    else:
        watch.record(t0, block.start, np.asarray(block.times, float), block.state_at,
                     block.rows, block.probe)


def completed(*outputs: np.ndarray) -> int:
    """The leading columns (grid points) every output of an interrupted integrator call has
    finite: those it had computed (runtime.buffers fills the rest with NaN)."""
    finite = np.ones(min(np.shape(out)[1] for out in outputs), bool)
    for out in outputs:
        finite &= np.all(np.isfinite(np.asarray(out)[:, :len(finite)]), axis=0)
    return int(np.argmin(finite)) if not finite.all() else len(finite)
