"""Running a study's points: in this process (workers 0) or through Dask.

Dask (`dask.distributed`, imported on use): a LocalCluster of `workers` processes with one
thread each, or the existing cluster at `scheduler`. A local cluster is this user's alone
(docs/security.md): its scheduler and workers listen on the loopback interface only, speak TLS
with temporary credentials made for it (distributed.security.Security.temporary: a client
without them is refused, so no other local user or process can submit a task), and serve no
HTTP routes (no dashboard, no metrics) unless `dashboard` asks for the dashboard, on loopback.
A remote scheduler is reached with the security of Dask's configuration (its TLS files) and a
short connection timeout: an address of the wrong form or where no scheduler answers is a
usage error. Consecutive runs go in one task of
batch.run_points (batch_size); each worker process prepares the job's runner once
(runner.runner_for), and a batched job's batch once (batch.batch_for), whose task is one
mapped call on the worker's thread. A batched job without a Dask cluster asked for (workers
None or 0, no scheduler) runs in this process, its mapped calls on the machine's cores.
Outcomes are handed to `done(index, outcome)` as they finish, in any order. SIGINT (Ctrl-C)
or SIGTERM stops the study: in this process through casmech.runtime.interrupts (the run in progress
stops at its next row and is not recorded); on Dask as a KeyboardInterrupt of the waiting
loop, which cancels what has not finished. What finished was already handed over.
"""

from __future__ import annotations

import logging
import os
import signal
import sys
import threading
from collections.abc import Callable, Sequence
from contextlib import contextmanager

from casmech.errors import UsageError
from casmech.runtime import interrupts
from casmech.study.batch import RUNS_PER_CALL, run_points
from casmech.study.runner import Job, Outcome, unexpected

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
            scheduler: str | None = None, dashboard: bool = False) -> bool:
    """Run every point; True when all ran, False when interrupted."""
    if scheduler is None and (workers == 0 or (workers is None and job.batched)):
        return _serial(job, points, done)
    return _dask(job, points, done, workers, scheduler, dashboard)


SCHEMES = ("tcp", "tls")  # a --scheduler address: SCHEME://HOST:PORT (tcp when left out)
CONNECT_TIMEOUT = "5s"  # a scheduler that does not answer by then is not there


def scheduler_address(address: str) -> str:
    """A scheduler's address checked for its form (a usage error otherwise), without
    connecting: tcp://HOST:PORT or tls://HOST:PORT (HOST:PORT means tcp)."""
    scheme, _, location = address.rpartition("://")
    host, _, port = location.rpartition(":")
    if (scheme or "tcp") not in SCHEMES or not host or not port.isdigit() \
            or not 0 < int(port) < 65536 or any(c.isspace() for c in address):
        raise UsageError(f"--scheduler '{address}' is not a Dask scheduler's address; "
                         "expected tcp://HOST:PORT or tls://HOST:PORT (e.g. "
                         "tls://cluster.example.org:8786)")
    return address if scheme else f"tcp://{address}"


def _connected(module, address: str):
    """A Client of the scheduler at `address` (a usage error when none answers)."""
    address = scheduler_address(address)
    try:
        return module.Client(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError, TypeError) as error:
        reason = str(error).strip().splitlines()[0] if str(error).strip() else \
            type(error).__name__
        raise UsageError(f"--scheduler {address}: no Dask scheduler answered within "
                         f"{CONNECT_TIMEOUT} ({reason[:200]}); is it running, and for tls://, "
                         "are Dask's TLS settings configured (docs/sweeps.md)?") from None


def local_cluster(module, workers: int, dashboard: bool = False):
    """A LocalCluster of `workers` processes that only this process can use (module
    docstring)."""
    import dask
    from distributed.security import Security

    routes = {} if dashboard else {"distributed.scheduler.http.routes": [],
                                   "distributed.worker.http.routes": []}
    # the workers inherit this configuration through their nanny
    with dask.config.set(routes), _signals(_workers_ignore_ctrl_c):
        return module.LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
            protocol="tls://", security=Security.temporary(),
            dashboard_address="127.0.0.1:0" if dashboard else None,
            # the scheduler's HTTP server (no routes without the dashboard) on a free port
            scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
            worker_dashboard_address=None, silence_logs=logging.ERROR,
            worker_class=module.Nanny)


def _serial(job: Job, points: Sequence[dict], done: Done) -> bool:
    with _signals(interrupts.trap):
        return _serial_runs(job, points, done)


def _serial_runs(job: Job, points: Sequence[dict], done: Done) -> bool:
    """SIGINT/SIGTERM (interrupts.trap) stop a run inside its integrator or at its next row,
    or after the run in progress when it came outside the analysis."""
    size, threads = (RUNS_PER_CALL, default_workers()) if job.batched else (1, 1)
    try:
        for start in range(0, len(points), size):
            interrupts.check()
            outcomes = run_points(job, points[start:start + size], threads)
            for index, outcome in enumerate(outcomes, start):
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
def client(workers: int | None, scheduler: str | None, dashboard: bool = False):
    """A dask.distributed Client of a new local cluster or of the one at `scheduler`."""
    module = distributed()
    if scheduler is not None:
        with _connected(module, scheduler) as connected:
            yield connected
        return
    cluster = local_cluster(module, workers or default_workers(), dashboard)
    with cluster, module.Client(cluster) as connected:
        if dashboard:
            print(f"sweep: Dask dashboard at {connected.dashboard_link}", file=sys.stderr)
        yield connected


def batch_size(points: int, workers: int, most: int = MAX_BATCH) -> int:
    """Runs per task: TASKS_PER_WORKER tasks per worker or more (so that the workers stay
    evenly loaded to the end), at most `most` runs each (so that progress and Ctrl-C stay
    prompt): MAX_BATCH run by run, batch.RUNS_PER_CALL for a batched job."""
    return max(1, min(most, points // (max(workers, 1) * TASKS_PER_WORKER)))


def _dask(job: Job, points: Sequence[dict], done: Done, workers: int | None,
          scheduler: str | None, dashboard: bool = False) -> bool:
    module = distributed()
    with client(workers, scheduler, dashboard) as connected, _signals(_terminate_interrupts):
        size = batch_size(len(points), len(connected.scheduler_info()["workers"]),
                          RUNS_PER_CALL if job.batched else MAX_BATCH)
        starts = range(0, len(points), size)
        batches = [list(points[k:k + size]) for k in starts]
        futures = connected.map(run_points, [job] * len(batches), batches, pure=False)
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
