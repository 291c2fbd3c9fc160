"""The compiled-model cache loads only what this user built, unchanged (backends.trust, issue
35 items 1 and 13): a library planted in an entry never runs (its constructor would write a
marker file), a damaged entry (a library cut short or emptied, a manifest of `{`) is built
again with a warning, a file or folder others could write is refused with a usage error, a
library is hashed and a manifest read once per process while their entry is unchanged, and a
build is private whatever the umask."""

import json
import os
import shutil
import stat
import subprocess
import sys
import time
import warnings
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from casmech.backends import cache, codegen, manifest, trust
from casmech.backends.build import LIBRARY
from casmech.cli import main
from tests.conftest import ROOT
from tests.helpers.codegen import MODEL

# a library whose constructor writes a marker when it is loaded: what an attacker would plant
PLANTED = """
#include <stdio.h>
__attribute__((constructor)) static void planted(void) {
    FILE *f = fopen("MARKER", "w"); if (f) { fputs("ran", f); fclose(f); }
}
int f(void) { return 0; }
"""


def _function() -> ca.Function:
    x = ca.SX.sym("x", 2)
    return ca.Function("f", [x], [ca.sin(x[0]) * x[1]], ["x"], ["y"])


def _compiled(toolchain, root: Path) -> dict:
    return codegen.compile_functions({"f": _function()}, toolchain=toolchain, root=root)


def _entry(root: Path) -> Path:
    (entry,) = cache.entries(root)
    return entry


def _plant(library: Path, marker: Path, toolchain) -> None:
    """Replace `library` by one whose constructor writes `marker`."""
    source = library.with_name("planted.c")
    source.write_text(PLANTED.replace("MARKER", str(marker)))
    subprocess.run([*toolchain.compiler.split(), "-shared", "-fPIC", str(source), "-o",
                    str(library)], check=True, capture_output=True)
    source.unlink()


def _value(functions) -> float:
    return float(functions["f"]([0.5, 2.0]))


def test_a_planted_library_never_runs_and_the_entry_is_rebuilt(toolchain, tmp_path):
    root, marker = tmp_path / "cache", tmp_path / "marker"
    _compiled(toolchain, root)
    _plant(_entry(root) / LIBRARY, marker, toolchain)
    with pytest.warns(UserWarning, match="is damaged .*sha256 differs.*building it again"):
        functions = _compiled(toolchain, root)
    assert not marker.exists()
    assert _value(functions) == pytest.approx(np.sin(0.5) * 2.0, rel=1e-15, abs=0)  # same C op
    assert manifest.sha256(_entry(root) / LIBRARY) == \
        manifest.read(_entry(root))[manifest.DIGESTS][LIBRARY]


def _cut(path: Path) -> None:
    path.write_bytes(path.read_bytes()[:len(path.read_bytes()) // 2])


DAMAGES = {
    "truncated library": lambda entry: _cut(entry / LIBRARY),
    "empty library": lambda entry: (entry / LIBRARY).write_bytes(b""),
    "missing library": lambda entry: (entry / LIBRARY).unlink(),
    "manifest {": lambda entry: (entry / manifest.MANIFEST).write_text("{"),
    "manifest without digests": lambda entry: (entry / manifest.MANIFEST).write_text(
        '{"functions": [{"name": "f"}]}'),
}


@pytest.mark.parametrize("damage", DAMAGES)
def test_a_damaged_entry_is_rebuilt_with_a_warning(toolchain, tmp_path, damage):
    root = tmp_path / "cache"
    _compiled(toolchain, root)
    DAMAGES[damage](_entry(root))
    with pytest.warns(UserWarning, match="is damaged"):
        functions = _compiled(toolchain, root)
    assert _value(functions) == pytest.approx(np.sin(0.5) * 2.0, rel=1e-15, abs=0)  # same C op
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _compiled(toolchain, root)  # whole again: a plain hit
    assert [p for p in root.iterdir() if p.name.startswith(".")] == []  # nothing left aside


def test_casmech_run_on_a_truncated_cached_library(toolchain, tmp_path, compiled, cache_root):
    """The reproducer of item 13 (a bus error, exit 135): in a fresh process, `casmech run`
    of the model whose cached library was cut short rebuilds it, warns and runs compiled."""
    root = tmp_path / "cache"
    for entry in cache.entries(cache_root):
        shutil.copytree(entry, root / entry.name)
    # the model libraries' entries (the session cache also holds other kinds' entries,
    # such as a joint system's, made by the folder's tests before this one)
    libraries = [entry / LIBRARY for entry in cache.entries(root) if (entry / LIBRARY).exists()]
    assert libraries
    for library in libraries:
        _cut(library)
    environment = {**os.environ, "CASMECH_CACHE_DIR": str(root),
                   "PYTHONPATH": str(ROOT / "src")}
    done = subprocess.run([sys.executable, "-m", "casmech.cli", "run", str(MODEL), "--out",
                           str(tmp_path / "out"), "--mode", "compiled"], env=environment,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "is damaged" in done.stderr and "building it again" in done.stderr
    assert '"mode": "compiled"' in (tmp_path / "out" / "metadata.json").read_text()


def test_a_group_writable_library_is_refused_and_never_loaded(toolchain, tmp_path):
    """A file others could have written is not rebuilt over: refused, naming it."""
    root, marker = tmp_path / "cache", tmp_path / "marker"
    _compiled(toolchain, root)
    library = _entry(root) / LIBRARY
    _plant(library, marker, toolchain)
    library.chmod(0o775)
    with pytest.raises(trust.Untrusted, match=f"{library} is writable by its group"):
        _compiled(toolchain, root)
    assert not marker.exists()


def test_casmech_run_refuses_a_planted_world_writable_library(toolchain, tmp_path, compiled,
                                                              cache_root, monkeypatch,
                                                              capsys):
    """The reproducer of item 1 through the command line: the model's cached entry holds a
    planted library others can write; `casmech run --mode compiled` exits 2 naming it, and
    the default mode (auto, which finds the entry cached) runs interpreted with the same
    message as a warning; the planted code runs in neither."""
    root, marker = tmp_path / "cache", tmp_path / "marker"
    for entry in cache.entries(cache_root):
        shutil.copytree(entry, root / entry.name)
    for entry in cache.entries(root):
        _plant(entry / LIBRARY, marker, toolchain)
        (entry / LIBRARY).chmod(0o777)
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(root))
    out = ["--out", str(tmp_path / "out")]
    assert main(["run", str(MODEL), *out, "--mode", "compiled"]) == 2
    assert "is writable by its group and others" in capsys.readouterr().err
    with pytest.warns(UserWarning, match="refusing the compiled-model cache"):
        assert main(["run", str(MODEL), *out]) == 0
    assert '"mode": "interpreted"' in (tmp_path / "out" / "metadata.json").read_text()
    assert not marker.exists()


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0,
                    reason="making a file another user's needs root")
def test_an_entry_owned_by_another_user_is_refused(toolchain, tmp_path):
    root, marker = tmp_path / "cache", tmp_path / "marker"
    _compiled(toolchain, root)
    library = _entry(root) / LIBRARY
    _plant(library, marker, toolchain)
    os.chown(library, 65534, 65534)
    with pytest.raises(trust.Untrusted, match="is owned by uid 65534, not by you"):
        _compiled(toolchain, root)
    assert not marker.exists()
    os.chown(root, 65534, 65534)
    with pytest.raises(trust.Untrusted, match=f"{root} is owned by uid 65534"):
        _compiled(toolchain, root)


def test_a_cache_folder_others_can_write_is_made_private(toolchain, tmp_path):
    root = tmp_path / "cache"
    root.mkdir()
    root.chmod(0o777)
    with pytest.warns(UserWarning, match=r"is writable by its group and others .*made it "
                                         r"private \(0700\)"):
        _compiled(toolchain, root)
    assert stat.S_IMODE(root.stat().st_mode) == 0o700


def test_a_new_build_is_private_whatever_the_umask(toolchain, tmp_path):
    previous = os.umask(0o002)
    try:
        _compiled(toolchain, tmp_path / "cache")
    finally:
        os.umask(previous)
    for path in [tmp_path / "cache", *(tmp_path / "cache").rglob("*")]:
        if path.suffix != ".lock":
            assert stat.S_IMODE(path.stat().st_mode) & 0o022 == 0, path
    assert stat.S_IMODE(_entry(tmp_path / "cache").stat().st_mode) == 0o700


def test_each_library_is_hashed_once_per_process(toolchain, tmp_path, monkeypatch):
    root = tmp_path / "cache"
    _compiled(toolchain, root)  # the build hashes it once to record it
    hashed = []
    original = trust.sha256

    def counting(path):
        hashed.append(Path(path).name)
        return original(path)

    monkeypatch.setattr(trust, "sha256", counting)
    trust._verified.clear()
    trust._manifests.clear()
    for _ in range(3):
        _compiled(toolchain, root)
    assert hashed == [LIBRARY]
    _cut(_entry(root) / LIBRARY)  # a changed file is hashed again ...
    with pytest.warns(UserWarning, match="is damaged"):
        _compiled(toolchain, root)  # ... and the entry rebuilt


def test_each_manifest_is_read_once_per_process_until_a_file_changes(toolchain, tmp_path,
                                                                     monkeypatch):
    """A lookup and a load verify an entry each; its manifest is read again only when one of
    the entry's files changed (here rewritten with the same content: another change time)."""
    root = tmp_path / "cache"
    _compiled(toolchain, root)
    read = []
    original = trust._manifest

    def counting(directory):
        read.append(directory.name)
        return original(directory)

    monkeypatch.setattr(trust, "_manifest", counting)
    trust._manifests.clear()
    for _ in range(3):
        # the compiled function's value: the same operations as numpy's, up to rounding
        np.testing.assert_allclose(_value(_compiled(toolchain, root)), np.sin(0.5) * 2.0,
                                   rtol=1e-14, atol=0)
    assert read == [_entry(root).name]
    written = _entry(root) / manifest.MANIFEST
    time.sleep(0.05)  # past a tick of the file system's clock
    written.write_bytes(written.read_bytes())
    _compiled(toolchain, root)
    assert len(read) == 2
    written.write_text("{")  # damaged after it was verified: seen, and the entry rebuilt
    with pytest.warns(UserWarning, match="is damaged"):
        _compiled(toolchain, root)


def test_cache_info_names_a_damaged_entry_and_escapes_names(toolchain, tmp_path, monkeypatch,
                                                            capsys):
    root = tmp_path / "cache"
    _compiled(toolchain, root)
    entry = _entry(root)
    record = manifest.read(entry)
    record["model"] = "evil\x1b[2J\nforged"
    (entry / manifest.MANIFEST).write_text(json.dumps(record))
    shutil.copytree(entry, root / ("0" * 32))
    (root / ("0" * 32) / manifest.MANIFEST).write_text("{")
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(root))
    assert main(["cache", "info"]) == 0
    out = capsys.readouterr().out
    assert f"{'0' * 32}  damaged: its manifest.json does not read" in out
    assert "evil\\x1b[2J\\nforged" in out and "\x1b" not in out
