"""A compiled joint tree's DAE residuals built on first use (backends.deferred): the bundle a
joint run loads is built without them, the run builds none, and the first read of one builds
them all once, in a cache entry of their own, equal to the interpreted residuals."""

import numpy as np

import casmech
from casmech.backends import cache, codegen, deferred, manifest
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
    assert all(name in functions.functions for name in names)  # named, not built
    assert len(builds) == 1 and not any(n.startswith("dae_") for n in _functions_in_cache(root)[0])

    result = casmech.analyze(functions, "dynamics", t_end=0.1, rtol=1e-8, atol=1e-10)
    assert result.metadata["formulation"] == "joint"
    assert all(not (set(names) & found) for found in _functions_in_cache(root))  # none built

    compiled_rp = functions["dae_rp"]
    assert sum(set(names) <= found for found in _functions_in_cache(root)) == 1
    residual_builds = len(builds)
    plain = casmech.compile(model)  # interpreted
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


def test_joint_tree_bundle_flags(monkeypatch):
    """The bundle of a joint tree is built at -O0 only where the user chose no flags: the
    default toolchain without $CASMECH_CFLAGS."""
    monkeypatch.delenv("CASMECH_CFLAGS", raising=False)
    assert deferred.bundle_toolchain(codegen.Toolchain()).flags == ("-O0",)
    chosen = codegen.Toolchain(flags=("-O2",))
    assert deferred.bundle_toolchain(chosen) is chosen
    monkeypatch.setenv("CASMECH_CFLAGS", "-O1")  # the default's value, chosen
    assert deferred.bundle_toolchain(codegen.Toolchain()).flags == ("-O1",)
