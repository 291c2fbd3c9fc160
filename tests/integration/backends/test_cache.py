"""The build cache: a hit for an unchanged model (API and `casmech run`), a rebuild for a changed
one, two processes building one model at once, `casmech cache info|clear`."""

import shutil
import subprocess
import sys

import numpy as np
import pytest

import casmech
from casmech.backends import cache, codegen
from casmech.backends.manifest import MANIFEST
from casmech.cli import main
from casmech.runtime import assembly
from tests.conftest import MODELS as MODELS_DIR
from tests.helpers.codegen import MODEL, counted_builds


@pytest.fixture
def builds(monkeypatch) -> list:
    """Records every build (the C compiler runs only inside build_libraries)."""
    return counted_builds(monkeypatch, codegen)


def test_unchanged_model_hits_changed_model_rebuilds(model, toolchain, cache_root, compiled,
                                                     builds):
    again = codegen.compiled(casmech.load(MODEL), toolchain, root=cache_root)
    assert builds == []  # the session fixture built it; same text, parameters, flags
    stiffer = casmech.load(MODEL, {"k": "25"})
    # without the DAE residuals: fewer libraries to build (the key says so)
    rebuilt = codegen.compiled(stiffer, toolchain, root=cache_root, dae=False)
    assert len(builds) == 1
    # the override reached the library: forces differ where the spring acts, as interpreted
    args = (0.1, assembly.initial_guess(again), np.zeros(14))
    want = casmech.compile(stiffer).vector("generalized_forces", *args)
    np.testing.assert_allclose(rebuilt.vector("generalized_forces", *args), want,
                               rtol=1e-12, atol=1e-12)  # compiled == interpreted bound
    assert not np.allclose(again.vector("generalized_forces", *args), want, rtol=1e-6, atol=0)


def test_flags_are_part_of_the_key(model):
    digest = cache.model_digest(model)
    assert cache.key(digest, "gcc 12", ("-O0",)) != cache.key(digest, "gcc 12", ("-O1",))
    assert cache.key(digest, "gcc 12", ("-O0",)) != cache.key(digest, "gcc 13", ("-O0",))


def test_second_casmech_run_does_not_recompile(tmp_path, compiled, builds):
    """`casmech run` of the unchanged model (built by the session fixture with the same flags):
    no build, twice (auto runs the cached library); after an edit of the file: one build with
    --mode compiled, none with auto (a model this small runs sooner interpreted)."""
    path = tmp_path / "m.yaml"
    path.write_text(MODEL.read_text())
    for _ in range(2):
        assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
        assert '"mode": "compiled"' in (tmp_path / "out" / "metadata.json").read_text()
    assert builds == []
    path.write_text(path.read_text().replace("stiffness: k,", "stiffness: 2 * k,"))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--t-end", "0.05"]) == 0
    assert '"mode": "interpreted"' in (tmp_path / "out" / "metadata.json").read_text()
    assert builds == []
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--t-end", "0.05",
                 "--mode", "compiled"]) == 0
    assert len(builds) == 1


BUILD_SCRIPT = """
import sys, casmech
from pathlib import Path
from casmech.backends import codegen
f = codegen.compiled(casmech.load(sys.argv[1]), codegen.Toolchain(flags=("-O0",)),
                     root=Path(sys.argv[2]), dae=False)
print(repr(f.vector("phi", 0.2, [0.1 * k for k in range(14)]).tolist()))
"""


def test_two_processes_building_one_model(tmp_path, interpreted, toolchain):
    """Started together on a cache holding only the debris of a killed build: both load a
    working library, one entry is published, no temporary directory of theirs is left, and
    the debris (maybe another live build's) is left alone."""
    root = tmp_path / "cache"
    debris = root / ".deadbeef.partial"
    debris.mkdir(parents=True)
    (debris / "casmech_model_0.c").write_text("int broken(")
    command = [sys.executable, "-c", BUILD_SCRIPT, str(MODEL), str(root)]
    processes = [subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                  text=True) for _ in range(2)]
    outputs = [p.communicate(timeout=120) for p in processes]
    assert [p.returncode for p in processes] == [0, 0], outputs
    want = interpreted.vector("phi", 0.2, [0.1 * k for k in range(14)])
    for out, _ in outputs:
        np.testing.assert_allclose(eval(out), want, rtol=1e-12, atol=1e-12)  # same operations
    assert len(cache.entries(root)) == 1
    hidden = [p for p in root.iterdir() if p.is_dir() and p.name.startswith(".")]
    assert hidden == [debris]


def test_cache_info_and_clear(tmp_path, compiled, cache_root, monkeypatch, capsys):
    root = tmp_path / "c"
    # the model's bundle (the session cache also holds the joint formulation's functions)
    entry = next(e for e in cache.entries(cache_root)
                 if "codegen_test" in (e / MANIFEST).read_text())
    shutil.copytree(entry, root / entry.name)
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(root))
    killed = root / f".{entry.name}.abc123"  # what a killed build leaves
    killed.mkdir()
    (killed / "casmech_model.c").write_text("x" * 2000)
    assert main(["cache", "info"]) == 0
    out = capsys.readouterr().out
    assert f"{root}: 1 compiled models" in out and "codegen_test" in out
    assert "and 1 unfinished builds (0.00 MB" in out
    assert main(["cache", "clear"]) == 0
    assert cache.entries(root) == [] and list(root.iterdir()) == []
    assert main(["cache", "info"]) == 0
    assert f"{root}: 0 compiled models" in capsys.readouterr().out


def _digest(path):
    return cache.model_digest(casmech.load(path))


def test_key_follows_table_data_and_component_files(tmp_path):
    """What a model reads besides its own text is in the key: an edited CSV value (table
    driver) and an edited component file (instances) each change it; reloading unchanged
    files does not."""
    models = MODELS_DIR
    shutil.copy(models / "table_driver.yaml", tmp_path)
    shutil.copy(models / "table_driver_profile.csv", tmp_path)
    shutil.copy(models / "quadruped_legs.yaml", tmp_path)
    shutil.copytree(models / "components", tmp_path / "components")
    for name, edited in (("table_driver.yaml", "table_driver_profile.csv"),
                         ("quadruped_legs.yaml", "components/leg.yaml")):
        before = _digest(tmp_path / name)
        assert _digest(tmp_path / name) == before  # deterministic
        text = (tmp_path / edited).read_text()
        # change one number that the model uses: a lift sample in a dwell / a leg's mass
        changed = text.replace("0.950,0\n", "0.950,0.0001\n") \
            if edited.endswith(".csv") else text.replace("mass: ", "mass: 1.5 * ", 1)
        assert changed != text
        (tmp_path / edited).write_text(changed)
        assert _digest(tmp_path / name) != before, edited
