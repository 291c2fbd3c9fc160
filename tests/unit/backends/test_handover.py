"""backends.handover without a build: when a handover polls its child, when it decides, and
that it never loads a library the child did not publish (a stand-in child process)."""

import copy

import pytest

from casmech.backends import background, handover
from casmech.backends.build import Toolchain
from casmech.backends.manifest import MANIFEST


class Child:
    """A stand-in for the build's Popen: running until `exit(code)`, its polls counted."""

    def __init__(self):
        self.returncode, self.polls = None, 0

    def poll(self):
        self.polls += 1
        return self.returncode

    def exit(self, code: int) -> None:
        self.returncode = code


def made(child, tmp_path) -> handover.Handover:
    return handover.Handover(None, "key", child, Toolchain(), tmp_path)


def test_no_build_started_no_handover(monkeypatch):
    monkeypatch.setattr(background, "_started", {"failed": None})
    assert handover.pending(None, None) is None
    assert handover.pending(None, "other") is None
    assert handover.pending(None, "failed") is None  # the child could not start


def test_a_handover_waits_for_its_own_build(monkeypatch, tmp_path):
    child = Child()
    monkeypatch.setattr(background, "_started", {"key": child})
    monkeypatch.setattr(handover.cache, "cache_dir", lambda: tmp_path)
    found = handover.pending(None, "key")
    assert found is not None and found.child is child and found.root == tmp_path


def test_one_poll_per_call_while_it_builds(tmp_path):
    child = Child()
    waiting = made(child, tmp_path)
    assert [waiting.ready() for _ in range(3)] == [None] * 3
    assert child.polls == 3


@pytest.fixture
def loads(monkeypatch) -> list:
    """codegen.compiled replaced by a stand-in returning "bundle": its calls."""
    calls = []
    monkeypatch.setattr(handover.codegen, "compiled",
                        lambda *args: calls.append(args) or "bundle")
    return calls


def published(root) -> None:
    (root / "key").mkdir()
    (root / "key" / MANIFEST).write_text("{}")


def test_a_published_library_is_loaded_once(tmp_path, loads):
    child = Child()
    waiting = made(child, tmp_path)
    published(tmp_path)
    assert waiting.ready() is None  # still running: not loaded though published
    child.exit(0)
    polls = child.polls
    assert [waiting.ready() for _ in range(3)] == ["bundle"] * 3
    assert len(loads) == 1 and child.polls == polls + 1


def test_a_failed_build_is_decided_once(tmp_path, loads):
    """A non-zero exit (killed): its library, even if published, is not loaded; no more polls."""
    child = Child()
    waiting = made(child, tmp_path)
    published(tmp_path)
    child.exit(-9)
    polls = child.polls
    assert [waiting.ready() for _ in range(3)] == [None] * 3
    assert loads == [] and child.polls == polls + 1


def test_a_clean_exit_without_the_library_is_decided_once(tmp_path, loads):
    """Exit 0 after leaving the build to another child: nothing to load, then no poll."""
    child = Child()
    waiting = made(child, tmp_path)
    child.exit(0)
    assert waiting.ready() is None
    published(tmp_path)  # by another process, later
    polls = child.polls
    assert waiting.ready() is None
    assert loads == [] and child.polls == polls


def test_a_copy_of_the_functions_shares_the_handover(tmp_path):
    waiting = made(Child(), tmp_path)
    assert copy.deepcopy(waiting) is waiting
