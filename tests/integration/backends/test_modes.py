"""casmech.compile(model, mode): auto falls back to interpreted with one warning when there is
no C compiler; compiled without one, or an unknown mode, is a usage error; casmech compile
writes its files into -o DIR."""

import warnings
from dataclasses import replace

import pytest

import casmech
from casmech.backends import cache, codegen
from casmech.cli import main
from casmech.core.options import DynamicsOptions
from casmech.errors import AnalysisError, UsageError
from tests.conftest import MODELS
from tests.helpers.codegen import MODEL


@pytest.fixture
def no_compiler(monkeypatch):
    monkeypatch.setenv("CC", "casmech-no-such-compiler")


def test_auto_without_compiler_warns_once_and_interprets(model, no_compiler):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        functions = casmech.compile(model, "auto")
    assert len(caught) == 1 and "no C compiler" in str(caught[0].message)
    assert codegen.mode_of(functions) == "interpreted"
    result = casmech.analyze(functions, "assembly")
    assert result.metadata["mode"] == "interpreted"


def test_compiled_without_compiler_is_a_usage_error(model, no_compiler, tmp_path, capsys):
    with pytest.raises(UsageError, match="no C compiler"):
        casmech.compile(model, "compiled")
    assert main(["compile", str(MODEL), "-o", str(tmp_path / "out")]) == 2
    assert "no C compiler" in capsys.readouterr().err


def test_unknown_mode_is_a_usage_error(model):
    with pytest.raises(UsageError, match="not one of interpreted, compiled, auto"):
        casmech.compile(model, "jit")


def test_auto_with_compiler_is_compiled(model, compiled, tmp_path, monkeypatch):
    assert codegen.mode_of(casmech.compile(model, "auto")) == "compiled"  # cached: compiled
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "empty"))
    # a cache miss on a model this small: interpreted is sooner end to end (AUTO_BODIES)
    assert codegen.mode_of(casmech.compile(model, "auto")) == "interpreted"
    assert not (tmp_path / "empty").exists()  # nothing was built


def test_compile_command_writes_sources_header_manifest_library(tmp_path, compiled, capsys):
    out = tmp_path / "out"
    assert main(["compile", str(MODEL), "-o", str(out)]) == 0
    assert "from the cache" in capsys.readouterr().out  # the session fixture built it
    names = {p.name for p in out.iterdir()}
    assert {"manifest.json", "casmech_model.h", "libcasmech_model.so"} <= names
    assert any(name.endswith(".c") for name in names)


def test_bad_jobs_is_a_usage_error(tmp_path, capsys):
    assert main(["compile", str(MODEL), "-o", str(tmp_path), "--jobs", "0"]) == 2
    assert "--jobs must be at least 1" in capsys.readouterr().err


@pytest.fixture
def failing_compiler(tmp_path, monkeypatch):
    """A 'compiler' that reports a version but fails every compilation."""
    script = tmp_path / "brokencc"
    script.write_text('#!/bin/sh\nif [ "$1" = --version ]; then echo brokencc 1.0; exit 0; fi\n'
                      'echo "brokencc: internal error" >&2; exit 1\n')
    script.chmod(0o755)
    monkeypatch.setenv("CC", str(script))


@pytest.fixture
def auto_compiles(monkeypatch):
    """auto decides to compile this small model on a cache miss (as it does from AUTO_BODIES
    bodies on, but for trees in joint coordinates), so what happens when compiling fails is
    exercised."""
    monkeypatch.setattr(codegen, "AUTO_BODIES", 1)
    monkeypatch.setattr(codegen, "_joint_tree", lambda model, ir: False)


def test_auto_falls_back_when_the_compiler_fails(model, failing_compiler, tmp_path,
                                                 monkeypatch, auto_compiles):
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        functions = casmech.compile(model, "auto")
    assert len(caught) == 1 and "the C compiler failed" in str(caught[0].message)
    assert codegen.mode_of(functions) == "interpreted"
    with pytest.raises(AnalysisError, match="brokencc: internal error"):
        casmech.compile(model, "compiled")
    assert cache.entries(tmp_path / "cache") == []  # nothing half-built published


def test_unwritable_cache(model, tmp_path, monkeypatch, capsys, auto_compiles):
    """A cache path that cannot be a directory: compiled is a usage error naming the variable,
    auto warns and interprets."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(blocker / "cache"))
    with pytest.raises(UsageError, match="CASMECH_CACHE_DIR"):
        casmech.compile(model, "compiled")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        functions = casmech.compile(model, "auto")
    assert len(caught) == 1 and "not writable" in str(caught[0].message)
    assert codegen.mode_of(functions) == "interpreted"


def test_output_path_that_is_a_file(tmp_path, capsys):
    target = tmp_path / "taken"
    target.write_text("")
    assert main(["compile", str(MODEL), "-o", str(target)]) == 2
    assert "-o expects a directory" in capsys.readouterr().err


def test_auto_mode_rule(model, compiled, cache_root, tmp_path, monkeypatch):
    """codegen.auto_mode: compiled when the library is cached; on a cache miss compiled from
    AUTO_BODIES bodies on (but for a tree run in joint coordinates), interpreted below;
    interpreted without a compiler."""
    assert len(model.bodies) < codegen.AUTO_BODIES
    assert codegen.is_cached(model, root=cache_root)  # the session fixture built it
    assert codegen.auto_mode(model, root=cache_root) == "compiled"
    empty = tmp_path / "empty"
    assert not codegen.is_cached(model, root=empty)
    assert codegen.auto_mode(model, root=empty) == "interpreted"
    assert not empty.exists()  # deciding builds nothing
    monkeypatch.setattr(codegen, "AUTO_BODIES", len(model.bodies))
    # a tree whose dynamics run in joint coordinates stays interpreted at every size; in rp, or
    # another analysis, it compiles from AUTO_BODIES bodies on, as loops do
    assert model.analysis.type == "dynamics"
    assert codegen.auto_mode(model, root=empty) == "interpreted"
    for analysis in (replace(model.analysis, options=DynamicsOptions(formulation="rp")),
                     replace(model.analysis, type="kinematics")):
        assert codegen.auto_mode(replace(model, analysis=analysis), root=empty) == "compiled"
    four_bar = casmech.load(MODELS / "four_bar.yaml")
    dynamics = replace(four_bar, analysis=replace(four_bar.analysis, type="dynamics"))
    monkeypatch.setattr(codegen, "AUTO_BODIES", len(four_bar.bodies))
    assert codegen.auto_mode(dynamics, root=empty) == "compiled"
    monkeypatch.setenv("CC", "casmech-no-such-compiler")
    assert codegen.auto_mode(model, root=cache_root) == "interpreted"
