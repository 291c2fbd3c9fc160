"""backends.stamps: a value is remembered across processes only under its files' stamps, in a
cache folder that is the user's, and a stored value is checked before it is used; the compiler's
version and casmech's source digest go through it and stay what they compute."""

import os
import subprocess
import sys

import pytest

from casmech.backends import build, cache, stamps

HEX = "0123456789abcdef" * 4


@pytest.fixture
def source(tmp_path):
    path = tmp_path / "source.txt"
    path.write_text("one")
    return path


def _counting(value):
    calls = []

    def compute():
        calls.append(1)
        return value

    return compute, calls


def test_a_stored_value_is_read_back_and_a_changed_file_computes_again(tmp_path, source,
                                                                       monkeypatch):
    root = tmp_path / "cache"
    root.mkdir(mode=0o700)
    monkeypatch.setattr(stamps, "RACY_SECONDS", -1.0)  # the file's fresh change time: stored
    compute, calls = _counting("value")
    for _ in range(2):
        assert stamps.remembered("k", [source], compute, str.isalpha, root) == "value"
    assert len(calls) == 1
    source.write_text("three")  # another size and change time
    assert stamps.remembered("k", [source], compute, str.isalpha, root) == "value"
    assert len(calls) == 2
    assert stamps.remembered("other kind", [source], compute, str.isalpha, root) == "value"
    assert len(calls) == 3


def test_a_file_changed_within_the_racy_seconds_is_not_stored(tmp_path, source):
    root = tmp_path / "cache"
    root.mkdir(mode=0o700)
    compute, calls = _counting("value")
    for _ in range(2):
        stamps.remembered("k", [source], compute, str.isalpha, root)
    assert len(calls) == 2 and not (root / stamps.FOLDER).exists()


def test_nothing_is_stored_without_a_cache_folder(tmp_path, source, monkeypatch):
    monkeypatch.setattr(stamps, "RACY_SECONDS", -1.0)
    compute, calls = _counting("value")
    for _ in range(2):
        stamps.remembered("k", [source], compute, str.isalpha, tmp_path / "missing")
    assert len(calls) == 2 and not (tmp_path / "missing").exists()


def _stored(root):
    (path,) = [p for p in (root / stamps.FOLDER).iterdir() if not p.name.startswith(".")]
    return path


@pytest.mark.skipif(not stamps.trust.POSIX, reason="mode bits are POSIX")
def test_a_stored_value_others_could_write_or_that_fails_its_check_is_not_used(
        tmp_path, source, monkeypatch):
    root = tmp_path / "cache"
    root.mkdir(mode=0o700)
    monkeypatch.setattr(stamps, "RACY_SECONDS", -1.0)
    compute, calls = _counting("value")
    stamps.remembered("k", [source], compute, str.isalpha, root)
    stored = _stored(root)
    stored.write_text("planted")
    stored.chmod(0o666)
    assert stamps.remembered("k", [source], compute, str.isalpha, root) == "value"
    stored.chmod(0o600)
    stored.write_text("not a value!")
    assert stamps.remembered("k", [source], compute, str.isalpha, root) == "value"
    assert len(calls) == 3
    assert stored.read_text() == "value"  # stored again
    stored.unlink()
    stored.symlink_to(source)
    assert stamps.remembered("k", [source], compute, str.isalpha, root) == "value"
    assert len(calls) == 4


def test_the_compiler_version_is_its_first_line_and_follows_the_program(tmp_path,
                                                                         monkeypatch):
    root = tmp_path / "cache"
    root.mkdir(mode=0o700)
    monkeypatch.setenv(cache.ENVIRONMENT, str(root))
    program = tmp_path / "bin" / "fakecc"
    program.parent.mkdir()
    program.write_text("")
    program.chmod(0o755)
    monkeypatch.setattr(stamps, "RACY_SECONDS", -1.0)
    monkeypatch.setenv("PATH", f"{program.parent}{os.pathsep}{os.environ['PATH']}")
    versions = []
    for text in ("fakecc 1.0", "fakecc 2.0.1"):
        program.write_text(f"#!/bin/sh\necho '{text}'\necho second line\n")
        for _ in range(2):  # the second from the stored value (a new process: no lru_cache)
            build.compiler_version.cache_clear()
            versions.append(build.compiler_version("fakecc"))
    assert versions == ["fakecc 1.0"] * 2 + ["fakecc 2.0.1"] * 2
    assert len(list((root / stamps.FOLDER).glob("[!.]*"))) == 2
    build.compiler_version.cache_clear()
    assert build.compiler_version("no-such-compiler-here") == ""


def test_the_source_digest_is_the_same_from_a_stored_value_and_read_again(tmp_path):
    """Two processes: the first stores it (the sources are older than the racy seconds in an
    installed tree; forced here), the second reads it; both equal the digest read afresh."""
    root = tmp_path / "cache"
    root.mkdir(mode=0o700)
    script = ("import sys; from casmech.backends import cache, stamps; "
              "stamps.RACY_SECONDS = -1.0; print(cache.source_digest())")
    env = {**os.environ, cache.ENVIRONMENT: str(root)}
    printed = [subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                              text=True, check=True).stdout.strip() for _ in range(2)]
    fresh = subprocess.run([sys.executable, "-c", script],
                           env={**env, cache.ENVIRONMENT: str(tmp_path / "none")},
                           capture_output=True, text=True, check=True).stdout.strip()
    assert printed == [fresh, fresh] and len(fresh) == 64
    assert len(list((root / stamps.FOLDER).glob("[!.]*"))) == 1

