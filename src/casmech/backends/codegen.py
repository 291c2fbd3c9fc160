"""Code generation: SystemFunctions -> C -> shared libraries -> casadi.external, with a cache.

    functions = compiled(model)           # SystemFunctions; built once per content, then cached
                                          # (once per structure for every parameter value when
                                          # codegen.parametric applies)
    export(model, Path("out"))            # `casmech compile`: sources, headers, manifest, libraries
    auto_mode(model)                      # "compiled" or "interpreted"
    compile_functions({"f": f}, ...)      # any named casadi Functions (codegen.library)

What is compiled (write_build):
  - the bundle, equations.functions.mapped_functions: every system function of the builder
    (equations.system) with its SX kernels (one per kind of constraint row, joint, body
    quantity, force element) mapped over their instances, with the derivatives casmech.optimal
    differentiates through (codegen.generate);
  - for a model whose analysis is kinematics or inverse dynamics, the prescribed-motion step
    over the bundle (formulations.prescribed.step), which runtime.kinematics maps over the output
    grid;
  - each DAE residual dae_[ggl_]<rp|romega> (formulations.residuals.oracles: a sum of elements,
    one kernel per joint, body and force element, the Jacobian from the kernels' own SX
    Jacobians; for a small model the inline SX), in a library of its own with the daeF and jacF
    casadi's IDAS interface loads from it; for a run of a tree in joint coordinates, which
    reads none of them and of the bundle only the assembly's functions, the bundle built with
    those alone and the rest and the residuals on first use instead, each in a cache entry of
    its own (backends.deferred).
The C holds each kernel once; only index tables grow with the model. Default flags -O1
(build.DEFAULT_FLAGS). The measurements behind this: docs/decisions/codegen-element-residuals.md.

`--mode auto` (auto_mode):
  - compiled when the library is in the cache (loading it is quick at any size);
  - otherwise compiled from AUTO_BODIES bodies on, interpreted below: interpreted is ready
    sooner up to 128 bodies, compiled from 256 for r-p dynamics (docs/decisions/mode-auto.md);
  - except a tree whose dynamics run in joint coordinates (its file's formulation auto or
    joint, no DAE stabilization): its ODE stays interpreted from solver.compile.ode_bodies bodies on
    (runtime.joint_dynamics) and the interpreted bundle builds only what the run reads, so it
    runs interpreted on a cache miss at every size (a formulation given on the command line
    is not seen here);
  - a cache miss run interpreted starts building the library in a process of its own while the
    run goes on (backends.background; $CASMECH_BACKGROUND_BUILD=0 turns it off), so that the
    next run of the unchanged model loads it compiled. casmech.compile's default is auto, and
    the analyses of its functions move to the library once that build has published it
    (auto_choice gives its key; backends.handover).
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import casadi as ca
import numpy as np

from casmech.backends import background as background_build
from casmech.backends import cache, deferred, manifest, parametric
from casmech.backends.build import LIBRARY, Toolchain, available, build_libraries
from casmech.backends.library import compile_functions
from casmech.backends.load import externals, mode_of
from casmech.backends.load import load as load_build
from casmech.core.last_call import last_call
from casmech.core.options import DynamicsOptions
from casmech.core.version import VERSION
from casmech.equations.evaluation import Evaluation, is_inline
from casmech.equations.functions import SystemFunctions, build_functions, mapped_functions
from casmech.errors import UsageError
from casmech.formulations import residuals
from casmech.formulations.tree import spanning_tree
from casmech.model.ir import ModelIR
from casmech.model.lower import lower
from casmech.schema.resolved import ResolvedModel

__all__ = ["Toolchain", "auto_choice", "auto_mode", "available", "compile_functions", "compiled",
           "export", "is_cached", "library_key", "mode_of", "parametric_functions",
           "write_build"]


def dae_oracles(ir: ModelIR) -> dict[str, dict[str, ca.Function]]:
    """Every DAE residual (both formulations, both stabilizations) with its daeF and jacF."""
    return residuals.oracles(ir)


PRESCRIBED_ANALYSES = ("kinematics", "inverse_dynamics")


def bundle(ir: ModelIR, names: tuple[str, ...] | None = None) -> dict[str, ca.Function]:
    """The functions of the bundle's library (module docstring): the builder's, mapped;
    prescribed_step over its functions evaluated inline (one SX graph) or mapped, as the
    switch says (equations.evaluation.WHERE_INLINE). `names`: only those of the builder's
    (a part of a joint tree's bundle, backends.deferred)."""
    from casmech.equations import system  # (on a build only: a warm run builds no function)
    from casmech.formulations import prescribed

    if names is not None:
        shared = system.System(ir, Evaluation.of(False, None))
        return {name: system.function(shared, name) for name in names}
    functions = mapped_functions(ir)
    if ir.analysis.type in PRESCRIBED_ANALYSES:
        over = build_functions(ir).functions if is_inline("prescribed_step", ir.n_bodies) \
            else functions
        functions["prescribed_step"] = prescribed.step(over)
    return functions


def write_build(ir: ModelIR, directory: Path, toolchain: Toolchain, info: dict,
                dae: bool = False, names: tuple[str, ...] | None = None) -> Path:
    """Generate the sources and headers, build the libraries and write the manifest (last, so
    a directory with a manifest is complete); `dae`: the DAE residuals dae_[ggl_]<formulation>
    too, each in its own library; `names`: only those of the bundle's functions."""
    from casmech.backends import generate  # (on a build only: a warm run writes no C)

    functions = bundle(ir, names)
    sources = generate.write_sources(functions, directory, toolchain.jobs)
    oracles = dae_oracles(ir) if dae else {}
    dae_sources = generate.write_dae_sources(oracles, directory)
    build_libraries({LIBRARY: sources, **dae_sources}, directory, toolchain)
    libraries = {name: generate.dae_library(name) for name in oracles}
    return manifest.write(directory, {**functions, **{name: oracle[name] for name, oracle in
                                                      oracles.items()}},
                          generate.differentiated(functions), {
        **info, "casmech": VERSION, "casmech_sources": cache.source_digest(),
        "casadi": ca.__version__, "compiler": toolchain.compiler,
        "compiler_version": toolchain.version(), "flags": list(toolchain.all_flags),
        "library": LIBRARY, "header": generate.HEADER,
        "sources": [s.name for s in sources + [p for group in dae_sources.values()
                                               for p in group]]}, libraries)


def _entry(model: ResolvedModel, ir: ModelIR, toolchain: Toolchain, dae: bool,
           mapped: bool = False, defer: bool = False
           ) -> tuple[str, Callable[[Path], None], tuple[np.ndarray, str] | None]:
    """(cache key, build(directory), (model data, signature)): the parametric library
    (codegen.parametric) where it applies and `mapped` is not asked for, with the values its
    load binds and the structure's signature, else the mapped one with the values baked in (and
    in its key), and None. With `defer` (a run's library), the mapped library of a joint tree
    (_deferred) holds only the functions its run reads (deferred.READ; the rest and the DAE
    residuals built on first use) and is built at -O0 where the user chose no flags
    (backends.deferred)."""
    if not mapped and parametric.applies(model):
        values, signature = _data(ir)  # one lowering's split serves key and load
        entry = parametric.key(model, signature, toolchain, dae)
        info = {"model": model.name, "key": entry}
        return entry, lambda directory: parametric.write_build(
            ir, directory, toolchain, info, dae, build_libraries), (values, signature)
    names = None
    if defer and _deferred(model, ir):
        dae, toolchain, names = False, deferred.bundle_toolchain(toolchain), deferred.READ
    model_hash = cache.model_digest(model)
    entry = cache.key(model_hash, toolchain.version(), toolchain.all_flags, dae, names)
    info = {"model": model.name, "model_hash": model_hash, "key": entry}
    return entry, lambda directory: write_build(ir, directory, toolchain, info, dae,
                                                names), None


def _model_data(ir: ModelIR) -> tuple[np.ndarray, str]:
    from casmech.model.parametric import data  # (on a parametric library's key only)

    return data(ir)


# model.parametric.data(ir), the same again for the IR split last: a run makes its library's
# entry twice (auto_choice looks it up, then compiled loads it); the IR is a frozen record
_data = last_call(_model_data)


def _deferred(model: ResolvedModel, ir: ModelIR) -> bool:
    """Whether most of the model's mapped library for a run and its DAE residuals wait for
    their first use (backends.deferred): a tree whose dynamics run in joint coordinates."""
    return _joint_tree(model, ir)


def _rest(model: ResolvedModel, ir: ModelIR, toolchain: Toolchain, bundle_key: str,
          root: Path | None) -> dict[str, ca.Function]:
    """The bundle's functions a joint tree's bundle was built without (deferred.rest), with
    the user's `toolchain`, loaded from their cache entry, built when it is missing."""
    names = deferred.rest()
    entry = deferred.key(bundle_key, "rest", toolchain)
    info = {"model": model.name, "model_hash": cache.model_digest(model), "key": entry}
    directory, _ = cache.lookup(entry, lambda directory: write_build(
        ir, directory, toolchain, info, False, names), root)
    return externals(directory)


def _residuals(model: ResolvedModel, ir: ModelIR, toolchain: Toolchain, bundle_key: str,
               root: Path | None) -> dict[str, ca.Function]:
    """The DAE residuals of a bundle built without them (backends.deferred), loaded from their
    cache entry, built when it is missing."""
    entry = deferred.key(bundle_key, "dae residuals", toolchain)
    info = {"model": model.name, "model_hash": cache.model_digest(model), "key": entry,
            "casmech": VERSION, "casmech_sources": cache.source_digest(),
            "casadi": ca.__version__, "compiler": toolchain.compiler,
            "compiler_version": toolchain.version(), "flags": list(toolchain.all_flags)}
    directory, _ = cache.lookup(entry, lambda directory: deferred.write_build(
        dae_oracles(ir), directory, info,
        lambda libraries, where: build_libraries(libraries, where, toolchain)), root)
    return externals(directory)


def _cached(model: ResolvedModel, toolchain: Toolchain, root: Path | None,
            dae: bool = False, mapped: bool = False, defer: bool = False
            ) -> tuple[Path, bool]:
    entry, build, _ = _entry(model, lower(model), toolchain, dae, mapped, defer)
    return cache.lookup(entry, build, root)


def compiled(model: ResolvedModel, toolchain: Toolchain | None = None,
             root: Path | None = None, dae: bool = True,
             parametric_library: bool = True) -> SystemFunctions:
    """The model's SystemFunctions loaded from its compiled libraries, built only when the
    cache holds none for this model (for a parametric library: this structure, whatever the
    parameter values; codegen.parametric), casmech/CasADi version, compiler and flags. With
    `dae`, the bundle also carries the DAE residuals dae_[ggl_]<formulation> as IDAS integrates
    them (t, x, z, p, u) -> (ode, alg, quad, zero) (formulations.dae.residual takes them from the
    bundle, formulations.dae.problem hands them to casadi as they are; a mapped library of a
    joint tree builds them on their first use: backends.deferred). `parametric_library` False:
    the mapped library even where the parametric one applies."""
    ir = lower(model)
    toolchain = toolchain or Toolchain()
    entry, build, bound = _entry(model, ir, toolchain, dae, not parametric_library, True)
    directory, _ = cache.lookup(entry, build, root)
    if bound is not None:
        return parametric.load(directory, ir, *bound)
    bundle = load_build(directory, ir)
    if _deferred(model, ir):
        later = [(deferred.rest(), lambda: _rest(model, ir, toolchain, entry, root))]
        if dae:
            later.append((deferred.residual_names(),
                          lambda: _residuals(model, ir, toolchain, entry, root)))
        bundle = replace(bundle, functions=deferred.with_deferred(bundle.functions, later))
    return bundle


def parametric_functions(model: ResolvedModel, toolchain: Toolchain | None = None,
                         root: Path | None = None, dae: bool = True
                         ) -> tuple[dict[str, ca.Function], np.ndarray]:
    """(the functions of the model's parametric library as built, each with the model data d
    its last input; the model's d), the library built as `compiled` builds it when the cache
    holds none: what runs many parameter sets through one call (casmech.study.batch) binds
    itself. A usage error when no parametric library applies (codegen.parametric.applies)."""
    if not parametric.applies(model):
        raise UsageError(f"model '{model.name}' has no parametric library (it needs parameters "
                         f"and at most {parametric.MAX_BODIES} bodies)")
    entry, build, values = _entry(model, lower(model), toolchain or Toolchain(), dae)
    directory, _ = cache.lookup(entry, build, root)
    return parametric.library_functions(directory), values


DYNAMICS = DynamicsOptions()  # the defaults (core.options)
AUTO_BODIES = 200  # module docstring: between 128 (interpreted sooner) and 256 (compiled sooner)


def _is_joint_tree(model: ResolvedModel, ir: ModelIR) -> bool:
    """Whether the model's dynamics run in joint coordinates on a tree (auto_mode)."""
    options, written = model.analysis.options, dict(model.analysis.written)
    if model.analysis.type != "dynamics":
        return False
    # (a block of another type's options run as dynamics: the keys its file wrote)
    formulation, stabilization = (getattr(options, key, written.get(key, getattr(DYNAMICS, key)))
                                  for key in ("formulation", "stabilization"))
    if formulation not in ("auto", "joint") or stabilization != DYNAMICS.stabilization:
        return False
    return spanning_tree(ir).is_tree


# _is_joint_tree, the same again for the (model, IR) asked last: a run asks up to four times
# (auto_choice's and compiled's entries, auto_choice, compiled's deferred parts); both are
# frozen records
_joint_tree = last_call(_is_joint_tree)


def _in_cache(model: ResolvedModel, ir: ModelIR, toolchain: Toolchain, root: Path | None,
              dae: bool = True) -> tuple[bool, str]:
    """(whether the cache holds the library compiled() loads, its entry)."""
    entry = _entry(model, ir, toolchain, dae, defer=True)[0]
    return (Path(root or cache.cache_dir()) / entry / manifest.MANIFEST).is_file(), entry


def is_cached(model: ResolvedModel, toolchain: Toolchain | None = None,
              root: Path | None = None, dae: bool = True) -> bool:
    """Whether the cache holds the model's library for this toolchain (nothing is built)."""
    return _in_cache(model, lower(model), toolchain or Toolchain(), root, dae)[0]


def auto_mode(model: ResolvedModel, toolchain: Toolchain | None = None,
              root: Path | None = None, background: bool = False) -> str:
    """"compiled" or "interpreted", whichever the model runs sooner without waiting long for a
    build (module docstring); "interpreted" without a C compiler. With `background`, a cache
    miss run interpreted also starts building the library behind the run
    (backends.background, unless $CASMECH_BACKGROUND_BUILD is 0), so later runs are compiled."""
    return auto_choice(model, toolchain, root, background)[0]


def auto_choice(model: ResolvedModel, toolchain: Toolchain | None = None,
                root: Path | None = None, background: bool = False) -> tuple[str, str | None]:
    """(auto_mode's choice, the cache key of the library a background build was asked to make
    or is making, when the choice is interpreted: None when none was)."""
    toolchain = toolchain or Toolchain()
    if not available(toolchain):
        return "interpreted", None
    ir = lower(model)
    hit, entry = _in_cache(model, ir, toolchain, root)
    if hit and background_build.running(entry, root):
        # its first part is published, the rest still building (this process's build, when
        # it started it: backends.handover follows it)
        return "interpreted", entry
    if hit or (len(model.bodies) >= AUTO_BODIES and not _joint_tree(model, ir)):
        return "compiled", None
    if background and background_build.enabled():
        background_build.start(model, toolchain, root, entry)
        return "interpreted", entry
    return "interpreted", None


def library_key(model: ResolvedModel, toolchain: Toolchain | None = None) -> str:
    """The cache key of the library `compiled(model, toolchain)` loads."""
    return _entry(model, lower(model), toolchain or Toolchain(), True, defer=True)[0]


def export(model: ResolvedModel, out: Path, toolchain: Toolchain | None = None,
           root: Path | None = None, dae: bool = True) -> tuple[Path, bool]:
    """Copy the model's build (through the cache) into `out`, by default with the DAE
    libraries (each DAE with daeF, jacF and its Jacobian: what a C integrator needs);
    (manifest path, cache hit)."""
    if out.exists() and not out.is_dir():
        raise UsageError(f"{out} is a file; -o expects a directory (created if missing)")
    directory, hit = _cached(model, toolchain or Toolchain(), root, dae, mapped=True)
    out.mkdir(parents=True, exist_ok=True)
    shutil.copytree(directory, out, dirs_exist_ok=True)
    return out / manifest.MANIFEST, hit
