"""The handover of an auto miss's functions to their compiled library: `casmech.compile(model)`
ran interpreted on a cache miss and started building the library behind (backends.background);
once that build has published it, the analyses of the same functions run on the compiled
bundle, loaded once, as `casmech.compile(model, "compiled")` loads it on a cache hit
(docs/decisions/mode-auto.md).

    handover = pending(model, key)   # None: no background build of this process to wait for
    handover.ready()                 # the compiled bundle, or None while it builds or after
                                     # it ended without a library

ready() never waits: while the build runs it costs one poll of the child process (waitpid
without blocking); once the child has exited it is decided for good: the bundle is loaded on
that call (a hit: nothing is generated or built) when the child published the library and
exited cleanly, and ready() returns it from then on; a build that failed, was killed or left
for another one leaves the functions interpreted, without an error, and is not looked at
again. The interpreted functions stay what they are (SX: symbolic calls, checks); the compiled
bundle is a bundle of its own, so what analyses keep for each (runtime.workspace) is apart.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

from casmech.backends import background, cache, codegen
from casmech.backends.build import Toolchain
from casmech.backends.manifest import MANIFEST
from casmech.equations.functions import SystemFunctions
from casmech.errors import CasmechError
from casmech.schema.resolved import ResolvedModel


class Handover:
    """The compiled bundle that `model`'s interpreted functions move to once the background
    build `child` has published the library `key` under `root` (module docstring)."""

    def __init__(self, model: ResolvedModel, key: str, child: subprocess.Popen,
                 toolchain: Toolchain, root: Path):
        self.model, self.key, self.child = model, key, child
        self.toolchain, self.root = toolchain, root
        self._decided = False
        self._compiled: SystemFunctions | None = None

    def ready(self) -> SystemFunctions | None:
        """The compiled bundle once the build has published it, else None (never waits)."""
        if self._decided or self.child.poll() is None:
            return self._compiled
        self._decided = True
        if self.child.returncode == 0 and (self.root / self.key / MANIFEST).is_file():
            try:
                self._compiled = codegen.compiled(self.model, self.toolchain, self.root)
            except (CasmechError, OSError, RuntimeError):  # gone or refused since: interpreted
                self._compiled = None
        return self._compiled

    def __deepcopy__(self, memo) -> Handover:
        return self  # the state of this process's build: a copy of the functions shares it

    def moved(self, model: ResolvedModel) -> Handover | None:
        """The handover of the same build for `model` (these functions' model at other
        parameter values: CompiledModel.set) where its library is the same one (a parametric
        library, the structure's), bound to its values on load; else None."""
        key = codegen.library_key(model, self.toolchain)
        return Handover(model, key, self.child, self.toolchain, self.root) \
            if key == self.key else None


def pending(model: ResolvedModel, key: str | None) -> Handover | None:
    """The handover of `model`'s functions built interpreted by auto while this process builds
    the library `key` behind (codegen.auto_choice); None where no such build was started."""
    child = background.child_of(key) if key is not None else None
    if child is None:
        return None
    return Handover(model, key, child, Toolchain(), cache.cache_dir())
