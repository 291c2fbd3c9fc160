"""The compiled bundle of a model whose dynamics run in joint coordinates on a tree: its DAE
residual libraries built when first read instead of with the bundle, the bundle itself at -O0
unless the user chose flags.

A tree's run in joint coordinates reads none of the residuals (runtime.joint_dynamics compiles
the tree's ODE and results rows itself), and they are most of the C of a cold build: four
residuals (rp and romega, both stabilizations) with their Jacobian blocks. So codegen.compiled
builds such a bundle without them, and the bundle's mapping (an
equations.functions.LazyFunctions) names them all the same; the first read of one (an rp or
romega run asked for) builds them all, with the user's toolchain, in a cache entry of their own
(`key`), once, and loads them from there afterwards. Of the bundle such a run reads little (the
assembly's functions, once), so gcc's optimization would lengthen the build for nothing.
Measurements: docs/decisions/deferred-dae-libraries.md.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable, Mapping
from pathlib import Path

import casadi as ca

from casmech.backends import generate, manifest
from casmech.backends.build import DEFAULT_FLAGS, FLAGS_ENVIRONMENT, Toolchain
from casmech.equations.functions import LazyFunctions
from casmech.formulations.registry import FORMULATIONS
from casmech.formulations.residuals import name

BUNDLE_FLAGS = ("-O0",)  # the bundle's, where the user chose no flags (module docstring)


def bundle_toolchain(toolchain: Toolchain) -> Toolchain:
    """`toolchain` with BUNDLE_FLAGS where its flags are the default and $CASMECH_CFLAGS is
    unset (no flags chosen)."""
    if toolchain.flags != DEFAULT_FLAGS or os.environ.get(FLAGS_ENVIRONMENT) is not None:
        return toolchain
    return Toolchain(toolchain.compiler, BUNDLE_FLAGS, toolchain.jobs)


def residual_names() -> tuple[str, ...]:
    """The names of the residuals a library compiles (formulations.residuals.oracles), without
    building them."""
    return tuple(name(formulation.name, kind) for formulation in FORMULATIONS.values()
                 for kind in formulation.library_stabilizations())


def key(bundle_key: str) -> str:
    """The cache key of the residuals of the bundle whose key is `bundle_key` (which records
    the model, versions, compiler and flags)."""
    return hashlib.sha256(f"{bundle_key} dae residuals".encode()).hexdigest()[:32]


def write_build(oracles: dict[str, dict[str, ca.Function]], directory: Path, info: dict,
                build: Callable[[dict[str, list[Path]], Path], list[Path]]) -> Path:
    """Each residual's library (generate.write_dae_sources) built by `build(libraries,
    directory)`, and the manifest listing the residuals."""
    sources = generate.write_dae_sources(oracles, directory)
    build(sources, directory)
    return manifest.write(directory, {n: oracle[n] for n, oracle in oracles.items()}, set(),
                          info, {n: generate.dae_library(n) for n in oracles})


def with_residuals(functions: Mapping[str, ca.Function],
                   residuals: Callable[[], Mapping[str, ca.Function]]) -> LazyFunctions:
    """The bundle's loaded `functions` and, named after them, the residuals `residuals()`
    loads (building them when the cache holds none) on the first read of one."""
    names = residual_names()
    lazy = LazyFunctions([(tuple(functions), lambda: list(functions.values())),
                          (names, lambda: [residuals()[n] for n in names])])
    lazy.given.update(functions)  # compiled externals: not SX (equations.functions.all_sx)
    return lazy
