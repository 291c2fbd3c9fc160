"""Running a study's points: in this process (workers 0) or through Dask.

Dask (`dask.distributed`, imported on use): a LocalCluster of `workers` processes with one
thread each, or the existing cluster at `scheduler`. Consecutive runs go in one task of
runner.run_batch (batch_size); each worker process prepares the job's runner once
(runner.runner_for).
Outcomes are handed to `done(index, outcome)` as they finish, in any order. SIGINT (Ctrl-C)
or SIGTERM stops the study: in this process through casmech.runtime.interrupts (the run in progress
stops at its next row and is not recorded); on Dask as a KeyboardInterrupt of the waiting
loop, which cancels what has not finished. What finished was already handed over.
"""

from __future__ import annotations

import logging
import os
import signal
import threading
from collections.abc import Callable, Sequence
from contextlib import contextmanager

from casmech.errors import UsageError
from casmech.runtime import interrupts
from casmech.study.runner import Job, Outcome, run_batch, unexpected

Done = Callable[[int, Outcome], None]
TASKS_PER_WORKER = 8  # batch_size: this many tasks per worker or more (when there are points)
MAX_BATCH = 16  # batch_size: at most this many runs per task


def default_workers() -> int:
    return os.cpu_count() or 1


def distributed():
    """dask.distributed, or a usage error saying how to install it."""
    try:
        import distributed as module
    except ImportError:
        raise UsageError("casmech sweep runs through Dask: install it with "
                         "pip install 'dask[distributed]' (or run in this process with "
                         "--workers 0)") from None
    return module


def execute(job: Job, points: Sequence[dict], done: Done, workers: int | None = None,
            scheduler: str | None = None) -> bool:
    """Run every point; True when all ran, False when interrupted."""
    if scheduler is None and workers == 0:
        return _serial(job, points, done)
    return _dask(job, points, done, workers, scheduler)


def _serial(job: Job, points: Sequence[dict], done: Done) -> bool:
    with _signals(interrupts.trap):
        return _serial_runs(job, points, done)


def _serial_runs(job: Job, points: Sequence[dict], done: Done) -> bool:
    """SIGINT/SIGTERM (interrupts.trap) stop a run inside its integrator or at its next row,
    or after the run in progress when it came outside the analysis."""
    try:
        for index, values in enumerate(points):
            interrupts.check()
            (outcome,) = run_batch(job, [values])
            done(index, outcome)
    except KeyboardInterrupt:  # errors.Interrupted is one
        return False
    return True


@contextmanager
def _signals(handling):
    """`handling()`'s signal handlers when this is the main thread (signals reach no other)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    with handling():
        yield


@contextmanager
def _terminate_interrupts():
    """SIGTERM stops the study as Ctrl-C does (a KeyboardInterrupt in the waiting loop)."""
    def handler(signum, frame):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextmanager
def _workers_ignore_ctrl_c():
    """SIGINT ignored while the local workers start: they inherit it, so a Ctrl-C at the
    terminal (sent to every process of the group) stops the study here, not them mid-task."""
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextmanager
def client(workers: int | None, scheduler: str | None):
    """A dask.distributed Client of a new local cluster or of the one at `scheduler`."""
    module = distributed()
    if scheduler is not None:
        with module.Client(scheduler) as connected:
            yield connected
        return
    count = workers or default_workers()
    with _signals(_workers_ignore_ctrl_c):  # the worker processes are started here
        cluster = module.LocalCluster(n_workers=count, threads_per_worker=1, processes=True,
                                      dashboard_address=":0", silence_logs=logging.ERROR,
                                      worker_class=module.Nanny)
    with cluster, module.Client(cluster) as connected:
        yield connected


def batch_size(points: int, workers: int) -> int:
    """Runs per task: TASKS_PER_WORKER tasks per worker or more (so that the workers stay
    evenly loaded to the end), at most MAX_BATCH runs each (so that progress and Ctrl-C stay
    prompt)."""
    return max(1, min(MAX_BATCH, points // (max(workers, 1) * TASKS_PER_WORKER)))


def _dask(job: Job, points: Sequence[dict], done: Done, workers: int | None,
          scheduler: str | None) -> bool:
    module = distributed()
    with client(workers, scheduler) as connected, _signals(_terminate_interrupts):
        size = batch_size(len(points), len(connected.scheduler_info()["workers"]))
        starts = range(0, len(points), size)
        batches = [list(points[k:k + size]) for k in starts]
        futures = connected.map(run_batch, [job] * len(batches), batches, pure=False)
        first = {future.key: k for k, future in zip(starts, futures, strict=True)}
        try:
            for future in module.as_completed(futures):
                k = first[future.key]
                batch = points[k:k + size]
                try:
                    outcomes = future.result()
                except Exception as error:  # noqa: BLE001  (a lost worker, a bug)
                    outcomes = [unexpected(values, error) for values in batch]
                for j, outcome in enumerate(outcomes):
                    done(k + j, outcome)
                future.release()
        except KeyboardInterrupt:
            connected.cancel(futures)
            return False
    return True
