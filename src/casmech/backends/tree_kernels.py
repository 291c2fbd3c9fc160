"""The per-joint kernels of a mapped tree (formulations/mapped_tree.py: the ODE's passes, for one
joint and for a block of a chain's joints; formulations/mapped_rows.py: the results rows' pose
and wrench passes) compiled once per joint type into a shared library of the compiled-model
cache, and loaded from it in every later process.

The kernels depend on the joint type alone (a body's data is an input), so one library per
joint type serves every model, and one more holds the kernels every tree calls (the per-body
rows, the multipliers): each cached by backends.library.compile_keyed under a key of its kind
and joint type and the versions, casmech's sources and the toolchain (a new CasADi or an edited
formulation builds it again), checked by backends.trust before it is loaded like any entry.
The Functions of the tree joints' rows (joint_system.rows_template, one per structure of a
joint's rows) are compiled under their content (backends.library.compile_functions). The
ODE's kernels are compiled with their forward derivatives (fwd1_<name>, which casadi.external
finds in the library), so the ODE's Jacobian is differentiated in compiled code. Without a C
compiler, or with a cache that cannot be written, there are no compiled kernels (one warning)
and runtime.joint_dynamics builds the tree unrolled, which evaluates faster than the kernels
interpreted.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from pathlib import Path

import casadi as ca

from casmech.backends import build
from casmech.backends.library import compile_functions, compile_keyed
from casmech.errors import AnalysisError, UsageError
from casmech.formulations import mapped_rows, mapped_tree
from casmech.formulations.tree import Tree
from casmech.model.ir import ModelIR

CONTENT = {"kind": "tree kernels", "passes": list(mapped_tree.PASSES),
           "constants": [mapped_tree.CONSTANTS, mapped_rows.POSE_CONSTANTS],
           "block": mapped_tree.BLOCK}


def _functions(kind: str) -> dict[str, ca.Function]:
    """A joint type's kernels (the ODE's and the results rows'), the ODE's with their forward
    derivatives under the names casadi.external looks them up."""
    ode = mapped_tree.kernels(kind) | mapped_tree.block_kernels(kind)
    return ode | {f"fwd1_{name}": f.forward(1) for name, f in ode.items()} | \
        mapped_rows.kernels(kind) | mapped_rows.block_kernels(kind)


def compiled(kinds, root: Path | None = None, toolchain: build.Toolchain | None = None
             ) -> dict[str, ca.Function]:
    """The kernels of the joint types `kinds` as externals of their cached libraries (one per
    joint type, built on a miss)."""
    toolchain = toolchain or build.Toolchain()
    found: dict[str, ca.Function] = {}
    for kind in sorted(set(kinds)):
        def make(kind=kind):
            return _functions(kind), {}, toolchain

        found |= compile_keyed(CONTENT | {"joint": kind}, make, toolchain=toolchain,
                               root=root)
    return found


def for_tree(ir: ModelIR, tree: Tree, root: Path | None = None,
             toolchain: build.Toolchain | None = None) -> dict[str, ca.Function]:
    """The compiled kernels a mapped tree calls: its joint types', the common ones
    (mapped_rows.common) and its joints' rows Functions (mapped_rows.templates, each compiled
    under its content), or none (kernels)."""
    return kernels({joint.type for joint in tree.joints}, root, toolchain,
                   mapped_rows.templates(ir, tree))


def kernels(kinds, root: Path | None = None, toolchain: build.Toolchain | None = None,
            rows: Mapping[str, ca.Function] | None = None) -> dict[str, ca.Function]:
    """The compiled kernels of the joint types `kinds` with the common ones and `rows` (rows
    Functions by name, compiled under their content), else (no C compiler, the build failed,
    no writable cache) none, with a warning saying why."""
    toolchain = toolchain or build.Toolchain()
    if not build.available(toolchain):
        warnings.warn(f"no C compiler '{toolchain.compiler}' found: the large tree is built "
                      "unrolled, which is slower to build; install gcc or set CC",
                      stacklevel=2)
        return {}
    try:
        found = compiled(kinds, root, toolchain)
        found |= compile_keyed(CONTENT | {"joint": "common"},
                               lambda: (mapped_rows.common(), {}, toolchain),
                               toolchain=toolchain, root=root)
        return found | (compile_functions(rows, toolchain=toolchain, root=root) if rows else {})
    except (AnalysisError, UsageError) as error:
        warnings.warn(f"{str(error).splitlines()[0]}; the large tree is built unrolled",
                      stacklevel=2)
        return {}
