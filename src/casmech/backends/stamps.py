"""Values derived from files, remembered across processes under the files' stamps.

A stamp is what `os.stat` says of each file the value was derived from: its path, device,
inode, size, modification and status-change times. A file written or replaced gets another
stamp (the status-change time is set by the system on every write, rename or new file and no
tool can set it back); so a value stored under a stamp is the value of the files as they are.
A value is stored only when none of its files changed in the last RACY_SECONDS (a file changed
again within one tick of the file system's clock would keep its stamp: git's "racy" case), and
only in a cache folder that already exists; nothing else creates or trusts it.

The values live in the cache folder's `stamps/` (one file a value, named by the sha256 of its
kind and stamp) and are read as untrusted: a file is used only when it is a regular file,
the user's and writable by no one else (codegen.trust.problem), and its text passes the
caller's check; anything else is computed again. Every failure to read or write falls back
to computing the value.
"""

from __future__ import annotations

import hashlib
import os
import stat
import tempfile
import time
from collections.abc import Callable, Iterable
from pathlib import Path

from casmech.backends import trust

FOLDER = "stamps"
RACY_SECONDS = 3.0
MAX_CHARS = 4096  # a stored value's largest size read


def stamp(paths: Iterable[str | os.PathLike]) -> tuple[list, float] | None:
    """(the files' stamp, the latest change time among them in seconds), or None when one
    of them cannot be read."""
    found, latest = [], 0.0
    try:
        for path in paths:
            status = os.stat(path)
            found.append([os.fspath(path), status.st_dev, status.st_ino, status.st_size,
                          status.st_mtime_ns, status.st_ctime_ns])
            latest = max(latest, status.st_mtime_ns, status.st_ctime_ns)
    except OSError:
        return None
    return found, latest / 1e9


def remembered(kind: str, paths: Iterable[str | os.PathLike], compute: Callable[[], str],
               check: Callable[[str], bool], root: Path | None) -> str:
    """compute(), the value of the files at `paths`, or the value stored under their stamp in
    `root`'s stamps/ when it passes `check` (module docstring); `kind` names what is
    computed (with anything else the value depends on)."""
    stamped = stamp(paths) if root is not None else None
    if stamped is None:
        return compute()
    files, latest = stamped
    name = hashlib.sha256(repr([kind, files]).encode()).hexdigest()[:32]
    stored = _read(root / FOLDER / name)
    if stored is not None and check(stored):
        return stored
    value = compute()
    if time.time() - latest > RACY_SECONDS and check(value):
        _write(root, name, value)
    return value


def _read(path: Path) -> str | None:
    """A stored value's text, when the folders and the file are the user's alone (else None)."""
    try:
        root, status = path.parent.parent, os.lstat(path)
        if trust.problem(root, root.stat()) or trust.problem(path.parent) or \
                trust.problem(path, status) or not stat.S_ISREG(status.st_mode) or \
                status.st_size > MAX_CHARS:
            return None
        return path.read_bytes().decode("utf-8")
    except (OSError, UnicodeDecodeError):
        return None


def _write(root: Path, name: str, value: str) -> None:
    """Store a value (one rename: a reader sees all of it or none), only in a cache folder
    that exists and is the user's."""
    folder = root / FOLDER
    try:
        if not root.is_dir() or trust.problem(root, root.stat()):
            return
        folder.mkdir(mode=0o700, exist_ok=True)
        if trust.problem(folder):
            return
        handle, temporary = tempfile.mkstemp(prefix=f".{name}.", dir=folder)
        try:
            with os.fdopen(handle, "wb") as file:
                file.write(value.encode("utf-8"))
            os.replace(temporary, folder / name)
        except OSError:
            Path(temporary).unlink(missing_ok=True)
    except OSError:
        pass
