"""A prepared run of joint coordinates (runtime.joint_dynamics.prepare): what a dynamics run
derives from its bundle and settings before it integrates (the joint system, the kept start,
method auto's choice, the Recorder, the integrator and its options, the output grid, the
metadata's names), held so that the same analysis run again on the same bundle and workspace
integrates at once (runtime.analyses keeps it in its plan).

A JointRun holds no bundle (it is kept in the bundle's workspace) and nothing a run returns:
each run makes its own Result, rows, chunks and metadata lists, and its own copy of the output
grid (a Result's blocks are views of the grid it was given).
"""

from __future__ import annotations

import numpy as np

from casmech.core.options import DynamicsSolver
from casmech.errors import AnalysisError, Interrupted
from casmech.runtime import events, nonfinite
from casmech.runtime.driver import Block, Chunks, completed, drive
from casmech.runtime.results import Result
from casmech.runtime.workspace import Workspace


class JointRun:
    """A run of joint coordinates from a kept start (x, z, loops) over `times`, by
    `integrate` (joint_dynamics' integrator, its options final), its rows by `recorder`;
    `derived`: the start's derived entries; `names`: (the tree's joint names, the cut joints'
    names) for the metadata; `model_events`: the model's events (runtime.events)."""

    def __init__(self, start: tuple, recorder, integrate, times: np.ndarray, rtol: float,
                 atol: float, settings: DynamicsSolver, workspace: Workspace,
                 names: tuple[tuple[str, ...], tuple[str, ...]], model_events: tuple):
        self.x, self.z, self.loops, self.derived = start
        self.recorder, self.integrate, self.times = recorder, integrate, times
        self.rtol, self.atol, self.settings, self.workspace = rtol, atol, settings, workspace
        self.names, self.dropped = names, int(self.loops.mask.sum())
        self.model_events = model_events
        method, cut = integrate.method, integrate.system.n_cut
        self.integrator = "dop853" if method == "dop853" else "idas" if cut else "cvodes"
        self.method = method if method == "dop853" or not cut else "bdf"

    def run(self, functions, progress=None, extra_events=()) -> Result:
        """The run's Result (its rows, events and metadata: runtime.joint_dynamics); the
        model's `events:` and `extra_events` (runtime.events.Event) are located and recorded
        in Result.events; without any, no event work is done."""
        recorder, integrate, loops = self.recorder, self.integrate, self.loops
        times = self.times.copy()  # the run's own: its Result's blocks are views of it
        settings = self.settings
        integrate.steps = 0
        cut = integrate.system.n_cut
        result = Result("dynamics", on_row=progress)
        watch = events.watch(functions, result, extra_events, self.rtol,
                             settings.event_iterations, self.workspace, self.model_events) \
            if self.model_events or extra_events else None  # (None: no event work)

        def block(t: float, chunk: np.ndarray, state) -> Block:
            """One solver call from (t, x, z) over `chunk` (z None: the loops' consistent
            multipliers at x, computed here; the next chunk's are never needed); the rows
            computed before a signal stopped it, attached to the Interrupted
            (runtime.driver)."""
            x, z = state
            if z is None:
                z = loops.z(t, x)
            try:
                states, algebraic = integrate(t, chunk, x, z)
            except Interrupted as interrupted:  # the grid points done before the signal
                done = getattr(interrupted, "outputs", None)
                count = 0 if done is None else completed(done["xf"], done["zf"])
                if count:
                    interrupted.block = made(t, chunk[:count], (x, z), done["xf"][:, :count],
                                             done["zf"][:, :count] if cut
                                             else np.zeros((0, count)))
                raise
            return made(t, chunk, (x, z), states, algebraic)

        def made(t: float, times_done: np.ndarray, start, states, algebraic) -> Block:
            def probe(t_start: float, at, t_trial: float, t_stop: float):
                """To t_stop, t_trial from the interpolant (as runtime.dynamics' probe: with
                loops, the index-2 DAE's first step is sized by the whole interval)."""
                found, found_z = integrate(t_start, [t_trial, t_stop], *at, trial=True)
                return (recorder.rows([t_trial], found[:, :1], found_z[:, :1]),
                        (found[:, 0], found_z[:, 0]))

            return Block(times_done, recorder.rows(times_done, states, algebraic),
                         (states[:, -1], None), start,
                         lambda j: (states[:, j], loops.z(times_done[j], states[:, j])), probe)

        x, z = self.x, self.z
        try:
            first, finite = recorder.first(times[0], x, z, self.derived)
            result.extend(times[:1], *first, checked=finite)  # (not finite: refused there)
            if watch is not None:
                watch.start(times[0], first)
            drive(result, times, (x, z), block, Chunks(settings.joint_chunk), watch,
                  halves=True, fail=nonfinite.interval_failure)
        except AnalysisError as error:
            error.partial = result
            raise
        tree, cut_joints = self.names
        result.metadata.update(
            rtol=self.rtol, atol=self.atol, formulation="joint", integrator=self.integrator,
            method=self.method, steps=integrate.steps, tree=list(tree),
            cut_joints=list(cut_joints), dropped_rows=self.dropped)
        return result
