"""backends.cache's listing of the sources its digest reads, against os.walk."""

import os

from casmech.backends import cache


def walked(folder: str) -> list[str]:
    """os.walk's .py files below `folder` (links to folders not followed), none in a bytecode
    folder."""
    return sorted(os.path.join(root, name) for root, _, files in os.walk(folder)
                  for name in files if name.endswith(".py")
                  and "__pycache__" not in root.split(os.sep))


def test_the_sources_are_the_python_files_os_walk_finds():
    for package in cache.SOURCE_PACKAGES:
        folder = str(cache.PACKAGE / package)
        assert sorted(cache._python_files(folder)) == walked(folder)
    listed = [path for _, path in cache._sources()]
    assert len(listed) == len(set(listed)) > 100


def test_bytecode_folders_are_not_read_and_linked_folders_not_followed(tmp_path):
    (tmp_path / "a" / "b").mkdir(parents=True)
    (tmp_path / "__pycache__").mkdir()
    for name in ("x.py", "a/y.py", "a/b/z.py", "a/notes.txt", "__pycache__/stray.py"):
        (tmp_path / name).write_text("")
    os.symlink(tmp_path / "a", tmp_path / "linked")
    os.symlink(tmp_path / "x.py", tmp_path / "alias.py")
    found = sorted(cache._python_files(str(tmp_path)))
    assert found == walked(str(tmp_path))
    assert [os.path.relpath(p, tmp_path) for p in found] == ["a/b/z.py", "a/y.py", "alias.py",
                                                              "x.py"]
