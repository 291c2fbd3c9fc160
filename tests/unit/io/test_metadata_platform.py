"""io.metadata.platform_text: metadata.json's platform, platform.platform() computed once and
then read back from the cache folder (backends.stamps)."""

import os
import platform

from casmech.backends import cache
from casmech.io import metadata


def test_the_platform_text_is_platform_platform_from_a_stored_value_too(tmp_path, monkeypatch):
    """metadata.json's platform: the same text computed and read back (a new process's)."""
    root = tmp_path / "cache"
    root.mkdir(mode=0o700)
    monkeypatch.setenv(cache.ENVIRONMENT, str(root))
    calls = []
    monkeypatch.setattr(platform, "platform", lambda: calls.append(1) or "Linux-6-x86_64-with-c")
    texts = [metadata.platform_text() for _ in range(2)]
    assert texts == ["Linux-6-x86_64-with-c"] * 2
    assert len(calls) == 1 or not hasattr(os, "uname")
