"""The child of a background build (backends.background starts it as
`python -m casmech.runtime.background_build FILE`): read and delete the model's pickle, take
the cache's background lock (or leave: another child is building), and while holding the lock
that marks the library as building (its file removed before the lock is let go), build the
library and, for dynamics, run the analysis over its first output step compiled with its
results table, which builds what a compiled `casmech run` of the model reads besides (a tree's
joint-system library, deferred functions)."""

from __future__ import annotations

import os
import pickle
import signal
import sys
from pathlib import Path

from filelock import FileLock, Timeout

from casmech.backends import cache, codegen
from casmech.backends.background import BACKGROUND_LOCK, BUILDING, LIMIT, NICENESS
from casmech.backends.build import Toolchain
from casmech.runtime.analyses import analyze
from casmech.runtime.results import table


def build(model, toolchain: Toolchain, root: Path | None) -> None:
    """The library, then for dynamics the analysis over its first output step, compiled, and
    its results table."""
    functions = codegen.compiled(model, toolchain, root)
    if model.analysis.type == "dynamics":
        step = min(model.analysis.output_step or model.analysis.t_end, model.analysis.t_end)
        table(functions, analyze(functions, "dynamics", t_end=step))


def main(path: str) -> int:
    if hasattr(os, "nice"):
        os.nice(NICENESS)
    if hasattr(signal, "alarm"):
        signal.alarm(LIMIT)
    try:
        with open(path, "rb") as stream:
            model, toolchain, root, key = pickle.load(stream)  # noqa: S301 - written by start()
    finally:
        os.unlink(path)
    folder = Path(root) if root is not None else cache.cache_dir()
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    marker = folder / f"{key}{BUILDING}"
    try:
        with FileLock(str(folder / BACKGROUND_LOCK), timeout=0), FileLock(str(marker)):
            try:
                build(model, Toolchain(toolchain.compiler, toolchain.flags, 1),
                      None if root is None else folder)
            finally:  # removed while held: a run that finds no marker needs no lock to know
                marker.unlink(missing_ok=True)  # no build runs (background.running)
    except Timeout:
        return 0  # another background build holds the cache: this one is not made
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
