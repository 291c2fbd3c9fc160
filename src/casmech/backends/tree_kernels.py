"""The per-joint kernels of the mapped tree ODE (formulations/mapped_tree.py) compiled once into
a shared library of the compiled-model cache, and loaded from it in every later process.

The kernels depend on the joint types alone (a body's data is an input), so one library serves
every model: it is cached by backends.library.compile_keyed under a key of its kind and the
versions, casmech's sources and the toolchain (a new CasADi or an edited formulation builds it
again), checked by backends.trust before it is loaded like any entry. Each kernel is compiled
with its forward derivative (fwd1_<name>, which casadi.external finds in the library), so an
MX graph over the kernels is differentiated in compiled code. Without a C compiler, or with a
cache that cannot be written, the interpreted kernels serve, with one warning.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import casadi as ca

from casmech.backends import build
from casmech.backends.library import compile_keyed
from casmech.errors import AnalysisError, UsageError
from casmech.formulations import mapped_rows, mapped_tree

CONTENT = {"kind": "tree kernels", "passes": list(mapped_tree.PASSES),
           "constants": mapped_tree.CONSTANTS}


def _functions() -> dict[str, ca.Function]:
    """Every kernel (the ODE's and the results rows') and its forward derivative under the
    name casadi.external looks it up."""
    kernels = mapped_tree.all_kernels() | mapped_rows.all_kernels()
    return kernels | {f"fwd1_{name}": f.forward(1) for name, f in kernels.items()}


def compiled(root: Path | None = None, toolchain: build.Toolchain | None = None
             ) -> dict[str, ca.Function]:
    """Every joint type's kernels as externals of the cached library (built on a miss)."""
    toolchain = toolchain or build.Toolchain()

    def make():
        return _functions(), {}, toolchain

    return compile_keyed(CONTENT, make, toolchain=toolchain, root=root)


def kernels(root: Path | None = None, toolchain: build.Toolchain | None = None
            ) -> dict[str, ca.Function]:
    """The compiled kernels, else (no C compiler, the build failed, no writable cache) the
    interpreted ones with a warning saying why."""
    toolchain = toolchain or build.Toolchain()
    if not build.available(toolchain):
        warnings.warn(f"no C compiler '{toolchain.compiler}' found: the large tree's ODE runs "
                      "its kernels interpreted, which is slower; install gcc or set CC",
                      stacklevel=2)
        return interpreted()
    try:
        return compiled(root, toolchain)
    except (AnalysisError, UsageError) as error:
        warnings.warn(f"{str(error).splitlines()[0]}; the large tree's ODE runs its kernels "
                      "interpreted", stacklevel=2)
        return interpreted()


def interpreted() -> dict[str, ca.Function]:
    """Every kernel as SX."""
    return mapped_tree.all_kernels() | mapped_rows.all_kernels()
