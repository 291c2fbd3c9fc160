"""The background build in tests (backends.background): the fixture that turns it on with a
private cache, and the wait for the children it started."""

import tempfile

import pytest

from casmech.backends import background, codegen

WAIT = 300  # s: a -O0 build of the gallery's small models takes seconds; the limit ends a hang


@pytest.fixture
def building(monkeypatch, tmp_path):
    """The background build on, a private cache and temporary folder, this process's record of
    started builds empty; yields the cache folder."""
    monkeypatch.setenv(background.ENVIRONMENT, "1")
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("CASMECH_CFLAGS", "-O0")
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(background, "_started", {})
    monkeypatch.setattr(background, "_children", [])
    if not codegen.available():
        pytest.skip("no C compiler")
    return tmp_path / "cache"


def finished(timeout: float = WAIT) -> list[int]:
    """Wait for every child this process started (each a detached process of its own); their
    exit codes."""
    return [child.wait(timeout=timeout) for child in background._children]
