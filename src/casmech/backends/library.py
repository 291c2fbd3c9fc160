"""Any named casadi Functions -> a cached compiled library -> loaded externals.

    compiled = compile_functions({"f": f, "dae": residual}, with_jacobian={"f"},
                                 integrators={"dae"})
    compiled["f"](x)                      # casadi.external, the same inputs and outputs as f
    ca.integrator("i", "idas", compiled["dae"], t0, grid)   # daeF/jacF from its library

The cache key is the functions' content (casadi's serialization of each, with its name and
what is generated with it), the CasADi and casmech versions, the C compiler and its flags: the
same functions build once, in a directory of the compiled-model cache (codegen.cache), and load
from it afterwards. `with_jacobian` adds jac_<name>, through which an MX graph over the external
is differentiated in compiled code. `integrators` names DAE residuals (t, x, z, p) -> (ode, alg)
(as formulations.dae builds them): each goes into a library of its own with its residual and
Jacobian blocks under the names casadi's IDAS interface looks up (daeF, jacF; the Jacobian by
CasADi's AD of the function), and comes back with the integrator's signature (t, x, z, p, u)
-> (ode, alg, quad, zero), ready for casadi.integrator or formulations.dae.problem. A
toolchain's function_flags compile the units of the functions they name with their own flags
(the functions grouped by flags, each group in units of its own), and are in the key.

`compile_keyed` caches the same kind of library under a key its caller gives (whatever the
functions are a function of), so that a cache hit builds no symbolic graph at all; functions it
is asked to keep rather than compile (evaluated a few times per run) are stored as CasADi's
serialization beside the library (<name>.casadi, checked like the library by codegen.trust) and
load interpreted.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

import casadi as ca

from casmech.backends import cache, manifest
from casmech.backends.build import LIBRARY, Toolchain, build_libraries
from casmech.backends.load import externals
from casmech.core.version import VERSION
from casmech.formulations import residuals

HEADER_PREFIX = "casmech_functions"


def content_key(functions: Mapping[str, ca.Function], with_jacobian: set[str],
                integrators: set[str], toolchain: Toolchain) -> str:
    """The cache key: every function's serialized content and role, and the toolchain."""
    entries = [[name, hashlib.sha256(function.serialize().encode()).hexdigest(),
                name in with_jacobian, name in integrators]
               for name, function in sorted(functions.items())]
    return _key("functions", toolchain, entries=entries)


def _key(kind: str, toolchain: Toolchain, **fields) -> str:
    """A library's cache key: `fields` (what its functions are), the versions, casmech's
    sources and the toolchain."""
    content = json.dumps({"format": manifest.FORMAT, "kind": kind, **fields, "casmech": VERSION,
                          "sources": cache.source_digest(), "casadi": ca.__version__,
                          "compiler": toolchain.version(), "flags": list(toolchain.all_flags),
                          "function_flags": [[n, list(f)] for n, f in
                                             sorted(toolchain.function_flags)]},
                         sort_keys=True)
    return hashlib.sha256(content.encode()).hexdigest()[:32]


def _named(name: str, function: ca.Function) -> ca.Function:
    """The function under `name` (the C symbol the library exports)."""
    if function.name() == name:
        return function
    symbols = function.sx_in() if function.is_a("SXFunction") else function.mx_in()
    return ca.Function(name, symbols, function.call(symbols), function.name_in(),
                       function.name_out())


def _check(functions: Mapping[str, ca.Function], with_jacobian: set[str],
           integrators: set[str]) -> None:
    unknown = (with_jacobian | integrators) - set(functions)
    if unknown:
        raise ValueError(f"not among the functions: {', '.join(sorted(unknown))}")
    for name in functions:
        if not name.isidentifier() or name in ("daeF", "jacF"):
            raise ValueError(f"{name!r} is not a usable C function name")
    for name in integrators:
        if functions[name].name_out() != ["ode", "alg"] or functions[name].n_in() != 4:
            raise ValueError(f"{name}: a DAE residual (t, x, z, p) -> (ode, alg) is expected")


def compile_functions(functions: Mapping[str, ca.Function], with_jacobian: Iterable[str] = (),
                      integrators: Iterable[str] = (), toolchain: Toolchain | None = None,
                      root: Path | None = None) -> dict[str, ca.Function]:
    """The functions compiled and loaded (casadi.external), by name; built only when the cache
    holds no library for this content and toolchain (module docstring)."""
    with_jacobian, integrators = set(with_jacobian), set(integrators)
    _check(functions, with_jacobian, integrators)
    toolchain = toolchain or Toolchain()
    named = {name: _named(name, f) for name, f in functions.items()}
    key = content_key(named, with_jacobian, integrators, toolchain)

    def build(directory: Path) -> None:
        _write(directory, key, named, {}, with_jacobian, integrators, toolchain)

    directory, _ = cache.lookup(key, build, root)
    return externals(directory)


def compile_keyed(content: Mapping, make: Callable[[], tuple[Mapping[str, ca.Function],
                                                              Mapping[str, ca.Function],
                                                              Toolchain]],
                  with_jacobian: Iterable[str] = (), integrators: Iterable[str] = (),
                  toolchain: Toolchain | None = None, root: Path | None = None
                  ) -> dict[str, ca.Function]:
    """Functions compiled and loaded as compile_functions does, cached under `content` (JSON:
    everything they are a function of, e.g. a model library's key and the settings that shape
    them) with the default `toolchain` instead of under their own serialization, so that a
    cache hit builds none of them. On a miss, make() -> (functions to compile, functions to keep
    as CasADi's serialization, the toolchain to build with: the default or one chosen from the
    functions, itself a function of `content`). Returns every function by name: the compiled
    ones as externals, the kept ones deserialized."""
    with_jacobian, integrators = set(with_jacobian), set(integrators)
    toolchain = toolchain or Toolchain()
    key = _key("keyed", toolchain, content=content, jacobian=sorted(with_jacobian),
               integrators=sorted(integrators))

    def build(directory: Path) -> None:
        compiled, kept, chosen = make()
        _check({**compiled, **kept}, with_jacobian, integrators)
        if with_jacobian & set(kept) or integrators & set(kept):
            raise ValueError("kept functions are neither differentiated nor integrators")
        _write(directory, key, {n: _named(n, f) for n, f in compiled.items()},
               {n: _named(n, f) for n, f in kept.items()}, with_jacobian, integrators, chosen)

    directory, _ = cache.lookup(key, build, root)
    return externals(directory)


def _write(directory: Path, key: str, named: Mapping[str, ca.Function],
           kept: Mapping[str, ca.Function], with_jacobian: set[str], integrators: set[str],
           toolchain: Toolchain) -> None:
    """A build directory: the C of `named` (their Jacobians with_jacobian; integrators as
    IDAS's DAE libraries) compiled, each function's units with its flags
    (toolchain.flags_of), `kept` serialized, and the manifest listing them all."""
    from casmech.backends import generate  # (on a build only: a warm run writes no C)

    plain = {n: f for n, f in named.items() if n not in integrators}
    by_flags: dict[tuple[str, ...], dict[str, list[ca.Function]]] = {}
    for n, f in plain.items():
        by_flags.setdefault(toolchain.flags_of(n), {})[n] = [
            f, *([f.jacobian()] if n in with_jacobian else [])]
    sets = generate.write_unit_sets(list(by_flags.values()), directory, toolchain.jobs,
                                    HEADER_PREFIX) if plain else []
    sources = [source for set_sources in sets for source in set_sources]
    unit_flags = {source.name: flags for flags, set_sources in zip(by_flags, sets, strict=True)
                  for source in set_sources if flags != tuple(toolchain.flags)}
    oracles = {n: residuals.from_residual(named[n]) for n in sorted(integrators)}
    dae_sources = generate.write_dae_sources(oracles, directory)
    build_libraries({LIBRARY: sources, **dae_sources} if sources else dae_sources,
                    directory, toolchain, unit_flags)
    for name, function in kept.items():
        function.save(str(directory / f"{name}{manifest.KEPT}"))
    manifest.write(directory, {**plain, **{n: o[n] for n, o in oracles.items()}, **kept},
                   with_jacobian, {
                       "model": "functions " + ", ".join(sorted({*named, *kept})),
                       "key": key, "casmech": VERSION, "casadi": ca.__version__,
                       "compiler": toolchain.compiler,
                       "compiler_version": toolchain.version(),
                       "flags": list(toolchain.all_flags), "library": LIBRARY,
                       "function_flags": {n: list(f) for n, f in toolchain.function_flags
                                          if n in plain}},
                   {**{n: generate.dae_library(n) for n in oracles},
                    **{n: f"{n}{manifest.KEPT}" for n in kept}})
