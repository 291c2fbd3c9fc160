"""Code generation: SystemFunctions -> C -> shared library -> casadi.external, with a cache.

    functions = compiled(model)           # SystemFunctions; built once per content, then cached
    export(model, Path("out"))            # `casmech compile`: sources, header, manifest, library
"""

from __future__ import annotations

import shutil
from pathlib import Path

import casadi as ca

import casmech
from casmech.codegen import cache, generate, manifest
from casmech.codegen.build import LIBRARY, Toolchain, available, build_library
from casmech.codegen.load import load as load_build
from casmech.codegen.load import mode_of
from casmech.codegen.mapped import mapped_functions
from casmech.compiler.functions import SystemFunctions
from casmech.compiler.lower import lower
from casmech.errors import UsageError
from casmech.schema.resolved import ResolvedModel

__all__ = ["Toolchain", "available", "compiled", "mode_of", "write_build", "export"]


def write_build(functions: dict[str, ca.Function], directory: Path, toolchain: Toolchain,
                info: dict, dae: bool = False) -> Path:
    """Generate the sources and header, build the library and write the manifest (last, so a
    directory with a manifest is complete); `dae`: the DAE residuals dae_<formulation> too."""
    functions = {**functions, **(generate.dae_functions(functions) if dae else {})}
    sources = generate.write_sources(functions, directory, toolchain.jobs)
    build_library(sources, directory, toolchain)
    return manifest.write(directory, functions, generate.differentiated(functions), {
        **info, "casmech": casmech.__version__, "casmech_sources": cache.source_digest(),
        "casadi": ca.__version__, "compiler": toolchain.compiler,
        "compiler_version": toolchain.version(), "flags": list(toolchain.all_flags),
        "library": LIBRARY, "header": generate.HEADER, "sources": [s.name for s in sources]})


def _cached(model: ResolvedModel, toolchain: Toolchain, root: Path | None,
            dae: bool = False) -> tuple[Path, bool]:
    model_hash = cache.model_digest(model.text, model.parameters)
    entry = cache.key(model_hash, toolchain.version(), toolchain.all_flags, dae)

    def build(directory: Path) -> None:
        write_build(mapped_functions(lower(model)), directory, toolchain,
                    {"model": model.name, "model_hash": model_hash, "key": entry}, dae)

    return cache.lookup(entry, build, root)


def compiled(model: ResolvedModel, toolchain: Toolchain | None = None,
             root: Path | None = None, dae: bool = True) -> SystemFunctions:
    """The model's SystemFunctions loaded from a compiled library, built only when the cache
    holds none for this model content, casmech/CasADi version, compiler and flags. With `dae`,
    the bundle also carries the DAE residuals dae_<formulation> with their Jacobians, which
    dynamics integrates instead of an MX graph over the other functions (measured 1.5x faster
    runs for 2.4x the build time: benchmarks/RESULTS_codegen.md)."""
    directory, _ = _cached(model, toolchain or Toolchain(), root, dae)
    return load_build(directory, lower(model))


def export(model: ResolvedModel, out: Path, toolchain: Toolchain | None = None,
           root: Path | None = None, dae: bool = True) -> tuple[Path, bool]:
    """Copy the model's build (through the cache) into `out`, by default with the DAE
    residuals and their Jacobians (what a C integrator needs); (manifest path, cache hit)."""
    if out.exists() and not out.is_dir():
        raise UsageError(f"{out} is a file; -o expects a directory (created if missing)")
    directory, hit = _cached(model, toolchain or Toolchain(), root, dae)
    out.mkdir(parents=True, exist_ok=True)
    shutil.copytree(directory, out, dirs_exist_ok=True)
    return out / manifest.MANIFEST, hit
