"""A compiled bundle's results row compiled under its library key (backends.results_row): the
same row as the one built over the bundle's functions (runtime.results.row_function), built
once and loaded afterwards, what a run's table maps; none for an interpreted or parametric
bundle, or without a C compiler."""

import numpy as np
import pytest

import casmech
from casmech.backends import cache, codegen, deferred, manifest, results_row
from casmech.runtime import results
from tests.helpers.codegen import counted_builds


@pytest.fixture
def mapped(model, toolchain, tmp_path, monkeypatch):
    """The session model's mapped library (a joint tree's: its rest deferred) in a cache of
    its own, which the results row's library goes to as well (the default cache folder)."""
    root = tmp_path / "cache"
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(root))
    return codegen.compiled(model, toolchain, root=root, parametric_library=False), root


def _names(root) -> list[set[str]]:
    return [{e["name"] for e in manifest.read(path)["functions"]} for path in cache.entries(root)]


def test_the_compiled_row_is_the_built_row(mapped):
    functions, root = mapped
    compiled = results_row.compiled(functions)
    assert compiled is not None and compiled.class_name() == "External"
    assert {results_row.NAME} in _names(root)
    assert not any("mass_matrix" in names for names in _names(root))  # no rest built
    built = results.row_function(functions)  # loads the rest, builds the readings
    rng = np.random.default_rng(7)
    for _ in range(5):
        args = [rng.uniform(-1, 1, built.sparsity_in(k).shape) for k in range(built.n_in())]
        # the same operations: the terms' C as their library's, the readings' as CasADi's
        # virtual machine evaluates them (no contraction under -std=c99): bit for bit
        got, want = np.array(compiled(*args)), np.array(built(*args))
        np.testing.assert_allclose(got, want, rtol=0, atol=0)
        np.testing.assert_array_equal(np.signbit(got), np.signbit(want))  # zeros' signs too


def test_a_run_maps_the_compiled_row_built_once(mapped, model, toolchain, monkeypatch):
    functions, root = mapped
    from casmech.backends import library

    builds = counted_builds(monkeypatch, library)
    result = casmech.analyze(functions, "dynamics", t_end=0.1)  # (builds the joint system)
    before = len(builds)
    names, values = results.table(functions, result)
    assert len(builds) == before + 1 and {results_row.NAME} in _names(root)
    assert not any(set(deferred.rest()) & found for found in _names(root))  # no rest built
    again = codegen.compiled(model, toolchain, root=root, parametric_library=False)
    assert results.row_call(again).class_name() == "External"
    assert len(builds) == before + 1  # loaded from the cache
    monkeypatch.setattr(results_row, "compiled", lambda functions: None)
    other = codegen.compiled(model, toolchain, root=root, parametric_library=False)
    want_names, want = results.table(other, result)  # row_function over the bundle
    assert names == want_names
    # the same operations (test above): bit for bit, the zeros' signs too (results.csv's text)
    np.testing.assert_allclose(values, want, rtol=0, atol=0)
    np.testing.assert_array_equal(np.signbit(values), np.signbit(want))


def test_no_compiled_row_for_an_interpreted_or_parametric_bundle(model, interpreted, compiled):
    assert results_row.compiled(interpreted) is None
    assert compiled.data is not None  # the session model's parametric library
    assert results_row.compiled(compiled) is None
    assert results.row_call(interpreted).class_name() in ("SXFunction", "MXFunction")


def test_no_compiled_row_without_a_compiler(mapped, monkeypatch):
    functions, root = mapped
    monkeypatch.setenv("CC", "no-such-compiler-casmech")
    assert results_row.compiled(functions) is None
    assert not any(results_row.NAME in names for names in _names(root))
    assert results.row_call(functions).class_name() == "MXFunction"
