"""The compiled bundle of a model whose dynamics run in joint coordinates on a tree: only the
functions its run reads (READ) built with it, the rest of the bundle and the DAE residual
libraries when first read, the bundle itself at -O0 unless the user chose flags.

A tree's run in joint coordinates reads of the bundle only the assembly's functions (READ,
once: runtime.assembly), and none of the residuals (runtime.joint_dynamics compiles the tree's
ODE and results rows itself), while the rest of the bundle and the four residuals (rp and
romega, both stabilizations, with their Jacobian blocks) would be most of its C. So
codegen.compiled builds such a bundle with READ alone, and the bundle's mapping (an
equations.functions.LazyFunctions) names every function all the same; the first read of one
of the rest (rest()) builds them all, and the first read of a residual builds the residuals,
each with the user's toolchain, in a cache entry of its own (`key`), once, and loads them from
there afterwards. The run calls READ a few times, so gcc's optimization would lengthen the
build for nothing.
Measurements: docs/decisions/deferred-dae-libraries.md.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable, Mapping
from pathlib import Path

import casadi as ca

from casmech.backends import manifest
from casmech.backends.build import DEFAULT_FLAGS, FLAGS_ENVIRONMENT, Toolchain
from casmech.equations.bundle_names import NAMES
from casmech.equations.functions import LazyFunctions
from casmech.formulations.registry import FORMULATIONS
from casmech.formulations.residuals import name

BUNDLE_FLAGS = ("-O0",)  # the bundle's, where the user chose no flags (module docstring)
READ = ("phi", "phi_q", "nu")  # the bundle's functions a joint tree's run reads (assembly)


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


def rest() -> tuple[str, ...]:
    """The bundle's functions a joint tree's bundle is built without, in the bundle's order."""
    return tuple(name for name in NAMES if name not in READ)


def key(bundle_key: str, part: str, toolchain: Toolchain) -> str:
    """The cache key of `part` (the rest, the residuals) of the bundle whose key is
    `bundle_key` (which records the model, versions and the bundle's compiler and flags),
    built with `toolchain`."""
    content = json.dumps([bundle_key, part, toolchain.version(), list(toolchain.all_flags)])
    return hashlib.sha256(content.encode()).hexdigest()[:32]


def write_build(oracles: dict[str, dict[str, ca.Function]], directory: Path, info: dict,
                build: Callable[[dict[str, list[Path]], Path], list[Path]]) -> Path:
    """Each residual's library (generate.write_dae_sources) built by `build(libraries,
    directory)`, and the manifest listing the residuals."""
    from casmech.backends import generate  # (on a build only: a warm run writes no C)

    sources = generate.write_dae_sources(oracles, directory)
    build(sources, directory)
    return manifest.write(directory, {n: oracle[n] for n, oracle in oracles.items()}, set(),
                          info, {n: generate.dae_library(n) for n in oracles})


def with_deferred(functions: Mapping[str, ca.Function],
                  later: list[tuple[tuple[str, ...], Callable[[], Mapping[str, ca.Function]]]]
                  ) -> LazyFunctions:
    """The bundle's loaded `functions` and, named after them, each group of `later` (its
    names, and what loads them, building them when the cache holds none) on the first read of
    one of its names."""
    groups = [(tuple(functions), lambda: list(functions.values()))]
    groups += [(names, lambda names=names, load=load: _listed(load(), names))
               for names, load in later]
    lazy = LazyFunctions(groups)
    lazy.given.update(functions)  # compiled externals: not SX (equations.functions.all_sx)
    return lazy


def _listed(loaded: Mapping[str, ca.Function], names: tuple[str, ...]) -> list[ca.Function]:
    return [loaded[name] for name in names]
