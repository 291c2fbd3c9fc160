"""Code generation: SystemFunctions -> C -> shared library -> casadi.external, with a cache.

    functions = compiled(model)           # SystemFunctions; built once per content, then cached
    export(model, Path("out"))            # `casmech compile`: sources, header, manifest, library
    auto_mode(model)                      # "compiled" or "interpreted": the faster end to end

What is compiled is codegen.mapped: every system function and the DAE residuals built from SX
kernels (one per kind of constraint row, body quantity, force element) mapped over their
instances, so the C holds each kernel once and only index tables grow with the model: YAML ->
loaded library for a 128-body chain in 6 s at -O0 and 16 s at -O1, 1000 bodies in 75 s and
113 s (the unrolled SX functions took 108-267 s at 128 bodies), on a shared, loaded 2-core VM.
Default flags -O0 (build.DEFAULT_FLAGS: within both targets; -O1 runs faster).
benchmarks/RESULTS_codegen.md has the measurements.

`--mode auto` (auto_mode) takes the path that is fastest end to end:
  - compiled when the library is in the cache (loading it takes 0.02-0.4 s);
  - otherwise compiled when the model has at least AUTO_BODIES bodies, interpreted below.
    Measured on chains (shared 2-core VM, RESULTS_codegen.md): YAML -> ready takes 0.05-1.1 s
    interpreted for 1-32 bodies against 1.5-8 s to build the library (the kernels' C is a
    fixed ~1.5 MB whatever the size), and 1 s of simulation runs about as fast either way;
    at 128 bodies 3.6 s against ~16 s. The interpreted SX bundle grows superlinearly (22 s
    at 256 bodies, 61 s at 512) and the build linearly (~75 s at 1000), so compiling pays
    from about 200 bodies even for a single run.
"""

from __future__ import annotations

import os
import shutil
import signal
from pathlib import Path

import casadi as ca

import casmech
from casmech.codegen import cache, generate, manifest, residuals
from casmech.codegen.build import LIBRARY, Toolchain, available, build_libraries
from casmech.codegen.library import compile_functions
from casmech.codegen.load import load as load_build
from casmech.codegen.load import mode_of
from casmech.codegen.mapped import mapped_functions
from casmech.compiler.formulations import FORMULATIONS
from casmech.compiler.functions import SystemFunctions
from casmech.compiler.ir import ModelIR
from casmech.compiler.lower import lower
from casmech.errors import UsageError
from casmech.schema.resolved import ResolvedModel

__all__ = ["Toolchain", "auto_mode", "available", "compile_functions", "compiled", "export",
           "is_cached", "mode_of", "write_build"]


def dae_oracles(ir: ModelIR) -> dict[str, dict[str, ca.Function]]:
    """Every DAE residual (both formulations, both stabilizations) with its daeF and jacF."""
    return {residuals.name(form, kind): residuals.oracle(ir, form, kind)
            for form in FORMULATIONS for kind in residuals.KINDS}


def write_build(ir: ModelIR, directory: Path, toolchain: Toolchain, info: dict,
                dae: bool = False) -> Path:
    """Generate the sources and headers, build the libraries and write the manifest (last, so
    a directory with a manifest is complete); `dae`: the DAE residuals dae_[ggl_]<formulation>
    too, each in its own library."""
    functions = mapped_functions(ir)
    sources = generate.write_sources(functions, directory, toolchain.jobs)
    oracles = dae_oracles(ir) if dae else {}
    dae_sources = generate.write_dae_sources(oracles, directory)
    build_libraries({LIBRARY: sources, **dae_sources}, directory, toolchain)
    libraries = {name: generate.dae_library(name) for name in oracles}
    return manifest.write(directory, {**functions, **{name: oracle[name] for name, oracle in
                                                      oracles.items()}},
                          generate.differentiated(functions), {
        **info, "casmech": casmech.__version__, "casmech_sources": cache.source_digest(),
        "casadi": ca.__version__, "compiler": toolchain.compiler,
        "compiler_version": toolchain.version(), "flags": list(toolchain.all_flags),
        "library": LIBRARY, "header": generate.HEADER,
        "sources": [s.name for s in sources + [p for group in dae_sources.values()
                                               for p in group]]}, libraries)


def _cached(model: ResolvedModel, toolchain: Toolchain, root: Path | None,
            dae: bool = False) -> tuple[Path, bool]:
    model_hash = cache.model_digest(model)
    entry = cache.key(model_hash, toolchain.version(), toolchain.all_flags, dae)

    def build(directory: Path) -> None:
        write_build(lower(model), directory, toolchain,
                    {"model": model.name, "model_hash": model_hash, "key": entry}, dae)

    return cache.lookup(entry, build, root)


def compiled(model: ResolvedModel, toolchain: Toolchain | None = None,
             root: Path | None = None, dae: bool = True) -> SystemFunctions:
    """The model's SystemFunctions loaded from a compiled library, built only when the cache
    holds none for this model content, casmech/CasADi version, compiler and flags. With `dae`,
    the bundle also carries the DAE residuals dae_<formulation> with their Jacobians, which
    dynamics integrates (compiler.dae.residual takes them from the bundle)."""
    directory, _ = _cached(model, toolchain or Toolchain(), root, dae)
    return load_build(directory, lower(model))


AUTO_BODIES = 200  # module docstring: the size from which compiling pays on a cache miss


def is_cached(model: ResolvedModel, toolchain: Toolchain | None = None,
              root: Path | None = None, dae: bool = True) -> bool:
    """Whether the cache holds the model's library for this toolchain (nothing is built)."""
    toolchain = toolchain or Toolchain()
    entry = cache.key(cache.model_digest(model), toolchain.version(),
                      toolchain.all_flags, dae)
    return (Path(root or cache.cache_dir()) / entry / manifest.MANIFEST).is_file()


def auto_mode(model: ResolvedModel, toolchain: Toolchain | None = None,
              root: Path | None = None, background: bool = False) -> str:
    """"compiled" or "interpreted", whichever the model runs sooner without waiting long for a
    build (module docstring); "interpreted" without a C compiler. With `background`, a cache
    miss below AUTO_BODIES also starts building the library behind the run when
    $CASMECH_BACKGROUND_BUILD is 1 (build_in_background), so later runs are compiled."""
    toolchain = toolchain or Toolchain()
    if not available(toolchain):
        return "interpreted"
    if is_cached(model, toolchain, root) or len(model.bodies) >= AUTO_BODIES:
        return "compiled"
    if background and os.environ.get(BACKGROUND_ENVIRONMENT) == "1":
        build_in_background(model, toolchain, root)
    return "interpreted"


BACKGROUND_ENVIRONMENT = "CASMECH_BACKGROUND_BUILD"  # "1": auto builds behind the run
BACKGROUND_LIMIT = 900  # s: a background build still running then stops (SIGALRM)


def build_in_background(model: ResolvedModel, toolchain: Toolchain | None = None,
                        root: Path | None = None) -> int:
    """Build the model's library into the cache in a detached process (two forks: no zombie,
    no wait at exit; one compiler process, niced), published atomically by cache.lookup, whose
    lock makes a foreground build of the same key wait for it instead of building twice.
    Returns the intermediate child's pid (0 where there is no fork)."""
    if not hasattr(os, "fork"):
        return 0
    toolchain = toolchain or Toolchain()
    pid = os.fork()
    if pid:
        os.waitpid(pid, 0)
        return pid
    try:
        os.setsid()
        if os.fork():
            os._exit(0)
        os.nice(10)
        signal.alarm(BACKGROUND_LIMIT)
        quiet = os.open(os.devnull, os.O_RDWR)
        for stream in (0, 1, 2):
            os.dup2(quiet, stream)
        _cached(model, Toolchain(toolchain.compiler, toolchain.flags, 1), root, True)
        os._exit(0)
    except BaseException:  # noqa: BLE001 - a detached child reports nothing and never returns
        os._exit(1)


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
