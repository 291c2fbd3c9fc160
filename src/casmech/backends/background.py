"""The background build: a model's library built into the cache by a process of its own while
the run that asked for it goes on interpreted (codegen.auto_mode), so that the model's next run
loads it compiled (docs/decisions/mode-auto.md).

  - on by default; $CASMECH_BACKGROUND_BUILD=0 turns it off;
  - the child is a fresh interpreter (`python -m casmech.runtime.background_build FILE`: it
    runs analyses, a layer above this one) in a session of its own, its output discarded,
    niced, stopped after LIMIT s: safe to start from a process running threads (a notebook, a
    Dask worker), where fork is not;
  - the model goes to it as a pickle in a private temporary file (mkstemp: 0600), written by
    this process and deleted by the child once read;
  - one at a time per cache: the child builds while it holds the cache's BACKGROUND_LOCK and
    leaves at once when another holds it; a process starts a given library's build once;
  - the child builds the library (codegen.compiled) and, for dynamics, runs the analysis
    compiled over its first output step with its results table, which builds what a compiled
    run reads besides (a tree's joint-system library, deferred functions); each is published
    through cache.lookup, whose lock makes a foreground build of the same key wait for it;
    while it builds it holds <key>BUILDING, and `running` tells auto to stay interpreted;
  - `child_of(key)` is the process this one started for a library: the functions of the miss
    move to the library once it has exited having published it (backends.handover).
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import subprocess

ENVIRONMENT = "CASMECH_BACKGROUND_BUILD"  # "0": auto never builds behind the run
LIMIT = 900  # s: a background build still running then stops (SIGALRM)
BACKGROUND_LOCK = "background.lock"  # in the cache folder: held by the one building child
BUILDING = ".background.lock"  # <library key> + BUILDING: held while it builds (cleared as locks)
NICENESS = 10
CHILD = "casmech.runtime.background_build"

_started: dict[str, subprocess.Popen | None] = {}  # library key -> the child started for it
_children: list[subprocess.Popen] = []  # kept to be reaped (poll) instead of left as zombies


def enabled() -> bool:
    """Whether auto builds behind the run ($CASMECH_BACKGROUND_BUILD is not "0")."""
    return os.environ.get(ENVIRONMENT, "1").strip() != "0"


def start(model, toolchain, root: Path | None, key: str) -> subprocess.Popen | None:
    """Start building the model's library (`key`: its cache entry) in a detached process,
    unless this process has started it already; the process, or None where none started."""
    for child in list(_children):
        if child.poll() is not None:
            _children.remove(child)
    if key in _started:
        return None
    _started[key] = None
    import pickle  # imported on use, as subprocess: a warm run starts no build
    import subprocess

    env = dict(os.environ)
    package_root = Path(__file__).resolve().parents[2]
    if package_root.name not in ("site-packages", "dist-packages"):  # this casmech, from src
        env["PYTHONPATH"] = os.pathsep.join(
            [str(package_root)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    path = None
    try:
        handle, path = tempfile.mkstemp(prefix="casmech-background-", suffix=".pickle")
        with os.fdopen(handle, "wb") as stream:
            pickle.dump((model, toolchain, None if root is None else str(root), key), stream)
        child = subprocess.Popen(  # noqa: S603 - this interpreter, this module, our own file
            [sys.executable, "-m", CHILD, path],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            env=env, close_fds=True, start_new_session=True)
    except (OSError, pickle.PicklingError, TypeError, AttributeError):  # no room for the
        if path is not None:  # file, an unpicklable model, no process: no build, and the run
            Path(path).unlink(missing_ok=True)  # that asked goes on interpreted
        return None
    _children.append(child)
    _started[key] = child
    return child


def child_of(key: str) -> subprocess.Popen | None:
    """The process this one started to build the library `key` (None: none started, or it
    could not start)."""
    return _started.get(key)


def running(key: str, root: Path | None) -> bool:
    """Whether a background build of the library `key` is under way: its first part may be in
    the cache already, the rest not (codegen.auto_mode counts that as a miss). The child
    removes its marker before it lets the lock go, so a warm run finds none and takes no lock;
    one a killed child left is probed (and found free)."""
    from casmech.backends import cache

    marker = Path(root or cache.cache_dir()) / f"{key}{BUILDING}"
    if not marker.exists():
        return False
    from filelock import FileLock, Timeout

    try:
        with FileLock(str(marker), timeout=0):
            return False
    except Timeout:
        return True
