"""The source digest in a library's key, remembered across processes (backends.stamps): an
edited source of the same size still changes it, in the next process, as reading every file
afresh does."""

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import casmech
from casmech.backends import cache, stamps

SCRIPT = ("from casmech.backends import cache, stamps; stamps.RACY_SECONDS = -1.0; "
          "print(cache.__file__, cache.source_digest())")


def _digest(src: Path, root: Path) -> str:
    """(module file, source digest) of a fresh process importing casmech from `src`."""
    done = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                          check=True, env={**os.environ, "PYTHONPATH": str(src),
                                           cache.ENVIRONMENT: str(root)})
    module, digest = done.stdout.split()
    assert Path(module).is_relative_to(src)  # the copy's sources, not the checkout's
    return digest


def test_an_edited_source_of_the_same_size_changes_the_digest_in_the_next_process(tmp_path):
    src = tmp_path / "src"
    shutil.copytree(Path(casmech.__file__).parent, src / "casmech",
                    ignore=shutil.ignore_patterns("__pycache__"))
    root = tmp_path / "cache"
    root.mkdir(mode=0o700)
    first = _digest(src, root)
    assert len(list((root / stamps.FOLDER).glob("[!.]*"))) == 1  # stored
    assert _digest(src, root) == first
    time.sleep(0.05)  # past a tick of the file system's clock
    edited = src / "casmech" / "equations" / "system.py"
    text = edited.read_text()
    edited.write_text(text.replace("\n", "\r", 1))  # one byte changed, the same size
    assert edited.stat().st_size == len(text.encode())
    second = _digest(src, root)
    assert second != first
    assert second == _digest(src, tmp_path / "none")  # read afresh: no cache folder
