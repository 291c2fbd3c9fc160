"""A compiled joint tree's bundle holds only what its run reads, the rest of the bundle and the
DAE residuals built on first use (backends.deferred): the run builds neither, the first read of
one builds its group once, in a cache entry of its own, equal to the interpreted functions; an
edited entry is not loaded but built again."""

import os

import numpy as np
import pytest

import casmech
from casmech.backends import cache, codegen, deferred, manifest, trust
from casmech.backends.build import LIBRARY
from casmech.formulations import dae


def _functions_in_cache(root) -> list[set[str]]:
    return [{entry["name"] for entry in manifest.read(path)["functions"]}
            for path in cache.entries(root)]


def test_joint_tree_builds_its_residuals_on_first_use(model, toolchain, tmp_path, monkeypatch):
    root = tmp_path / "cache"
    builds = []
    original = codegen.build_libraries
    monkeypatch.setattr(codegen, "build_libraries",
                        lambda libraries, *args: builds.append(set(libraries))
                        or original(libraries, *args))
    # the mapped library (the session model also has a parametric one, which keeps them)
    functions = codegen.compiled(model, toolchain, root=root, parametric_library=False)
    names = deferred.residual_names()
    assert set(names) == {"dae_rp", "dae_ggl_rp", "dae_romega", "dae_ggl_romega"}
    assert all(name in functions.functions for name in (*names, *deferred.rest()))  # named
    assert len(builds) == 1 and _functions_in_cache(root) == [set(deferred.READ)]

    result = casmech.analyze(functions, "dynamics", t_end=0.1, rtol=1e-8, atol=1e-10)
    assert result.metadata["formulation"] == "joint"
    assert all(not ({*names, *deferred.rest()} & found)
               for found in _functions_in_cache(root))  # none built

    compiled_rp = functions["dae_rp"]
    assert sum(set(names) <= found for found in _functions_in_cache(root)) == 1
    residual_builds = len(builds)
    plain = casmech.compile(model, "interpreted")
    rng = np.random.default_rng(5)
    for name, (form, kind) in {"dae_rp": ("rp", "projection"),
                               "dae_ggl_romega": ("romega", "ggl")}.items():
        interpreted = dae.residual(plain.functions, form, kind)
        args = [rng.standard_normal(interpreted.sparsity_in(k).shape) for k in range(4)]
        got = (compiled_rp if name == "dae_rp" else functions[name])(*args, [])
        for g, w in zip(got[:2], interpreted(*args), strict=True):
            # the same SX expressions, in C against casadi's virtual machine: round-off
            np.testing.assert_allclose(np.array(g), np.array(w), rtol=1e-12, atol=1e-12)

    again = codegen.compiled(model, toolchain, root=root, parametric_library=False)
    again["dae_ggl_rp"]
    assert len(builds) == residual_builds  # both entries loaded from the cache


def _rest_entry(root):
    (entry,) = [path for path in cache.entries(root)
                if "mass_matrix" in {e["name"] for e in manifest.read(path)["functions"]}]
    return entry


def test_the_rest_of_a_joint_trees_bundle_is_built_on_first_read(model, toolchain, tmp_path,
                                                                 interpreted):
    root = tmp_path / "cache"
    functions = codegen.compiled(model, toolchain, root=root, parametric_library=False)
    assert len(cache.entries(root)) == 1
    rng = np.random.default_rng(3)
    q = rng.uniform(-1, 1, interpreted.n_coordinates)
    mass = np.array(functions["mass_matrix"](q))  # builds the rest
    entry = _rest_entry(root)
    assert {e["name"] for e in manifest.read(entry)["functions"]} == set(deferred.rest())
    # the same SX compiled to C against casadi's virtual machine: round-off
    np.testing.assert_allclose(mass, np.array(interpreted["mass_matrix"](q)), rtol=1e-12,
                               atol=1e-12)
    args = [rng.uniform(-1, 1, interpreted["energy"].sparsity_in(k).shape)
            for k in range(interpreted["energy"].n_in())]
    for got, want in zip(functions["energy"](*args), interpreted["energy"](*args), strict=True):
        np.testing.assert_allclose(np.array(got), np.array(want), rtol=1e-12, atol=1e-12)

    library = entry / manifest.read(entry)["library"]
    edited = entry / "edited"  # (a new file: the loaded library's pages stay as they are)
    edited.write_bytes(library.read_bytes() + b"\0")
    os.replace(edited, library)  # the library edited after its build
    with pytest.raises(trust.Corrupt, match="sha256 differs"):
        trust.verify(entry, LIBRARY)  # what cache.lookup checks before a load


def test_joint_tree_bundle_flags(monkeypatch):
    """The bundle of a joint tree is built at -O0 only where the user chose no flags: the
    default toolchain without $CASMECH_CFLAGS."""
    monkeypatch.delenv("CASMECH_CFLAGS", raising=False)
    assert deferred.bundle_toolchain(codegen.Toolchain()).flags == ("-O0",)
    chosen = codegen.Toolchain(flags=("-O2",))
    assert deferred.bundle_toolchain(chosen) is chosen
    monkeypatch.setenv("CASMECH_CFLAGS", "-O1")  # the default's value, chosen
    assert deferred.bundle_toolchain(codegen.Toolchain()).flags == ("-O1",)
