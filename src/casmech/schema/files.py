"""The files a model names (component files, tables, meshes, estimation data): where they may
be, and reading them with a bound on their size.

A path in a model is relative to the file that names it. It must resolve (symbolic links
followed) inside the folder of the model file being loaded or inside an allowed folder: those
in the environment variable CASMECH_ALLOWED_DIRS (separated by os.pathsep) and those given by
`--allow-dir DIR` on the command line (`allow`). Elsewhere it is E305, and so is anything but a
regular file (a device, a FIFO, a folder): a model cannot make casmech read /dev/zero, the
process environment or another user's files, and an error message never shows such a file.

A file is read up to a limit (E306 beyond it; E006 for the model file itself): a device or a
huge file costs at most the limit in time and memory.

While a model loads (`rooted`), every file it names that exists is recorded; `digests` gives
their sha256 for the run's metadata (io/metadata.py) and `casmech run --replay`. Every path it
names, present or not, is recorded too with where it resolved (`asked`): what a kept model
(backends.checked_model) checks again before it stands for a new load.
"""

from __future__ import annotations

import hashlib
import os
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

MAX_MODEL_BYTES = 2 << 20  # a model or component file: the gallery's are 3-5 kB, a 1000-body
#                           model written out 80 kB; bounds the time to read one
#                           (docs/decisions/hostile-input.md)
MAX_TABLE_BYTES = 8 << 20  # a CSV table: 200 000 rows of a few columns
ALLOWED_DIRS = "CASMECH_ALLOWED_DIRS"

_extra: list[Path] = []  # folders allowed by `allow` (the command line)
_roots: ContextVar[tuple[Path, ...] | None] = ContextVar("casmech_model_roots", default=None)
_named: ContextVar[dict[str, Path] | None] = ContextVar("casmech_model_files", default=None)
# the path each name resolved from (its base file's folder joined with it) -> where it resolved
_asked: ContextVar[dict[str, str] | None] = ContextVar("casmech_model_names", default=None)
MAX_HASH_BYTES = 256 << 20  # a file named by a model is hashed up to this size (meshes)


class TooLarge(OSError):
    """The file holds more than the limit (`size` is what was seen: limit + 1 at least)."""

    def __init__(self, size: int):
        super().__init__(f"larger than the limit ({size} bytes or more)")
        self.size = size


class NotAllowed(Exception):
    """A path a model may not name; `reason` says why (no file content)."""

    def __init__(self, reason: str, hint: str):
        super().__init__(reason)
        self.reason, self.hint = reason, hint


def allow(folder: str | os.PathLike) -> None:
    """Allow models to name files under `folder` (for this process)."""
    _extra.append(Path(folder).expanduser().resolve())


def allowed_folders(model_file: str) -> tuple[Path, ...]:
    """The folder of `model_file`, then the allowed folders."""
    environment = [Path(p).expanduser().resolve()
                   for p in os.environ.get(ALLOWED_DIRS, "").split(os.pathsep) if p.strip()]
    return (Path(model_file).resolve().parent, *environment, *_extra)


@contextmanager
def rooted(model_file: str) -> Iterator[dict[str, Path]]:
    """Within this block, paths resolve inside the folder of `model_file` (the model being
    loaded; its component files stay under the same folders). Yields the files named so far
    (absolute path text -> Path), filled as `resolve` finds them."""
    if _roots.get() is not None:  # a nested load (a component file) keeps the outer roots
        yield _named.get()
        return
    named: dict[str, Path] = {}
    token, recording = _roots.set(allowed_folders(model_file)), _named.set(named)
    asking = _asked.set({})
    try:
        yield named
    finally:
        _asked.reset(asking)
        _named.reset(recording)
        _roots.reset(token)


def asked() -> dict[str, str]:
    """Within `rooted`: every path the load has resolved so far, existing or not (its base
    file's folder joined with the name as written -> the resolved path)."""
    return dict(_asked.get() or {})


def resolve(base_file: str, name: str, *, must_exist: bool = True) -> Path:
    """The file `name` (relative to the folder of `base_file`), checked: inside an allowed
    folder and, when it exists (or must), a regular file. Raises NotAllowed or
    FileNotFoundError."""
    roots = _roots.get() or allowed_folders(base_file)
    joined = Path(base_file).parent / name
    path = joined.resolve()
    if not any(path == root or root in path.parents for root in roots):
        raise NotAllowed("the path leads outside the model's folder",
                         f"files a model names must be in its folder ({roots[0]}) or below; "
                         f"allow more with --allow-dir DIR or ${ALLOWED_DIRS}")
    asking = _asked.get()
    if asking is not None:
        asking[str(joined)] = str(path)
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        if must_exist:
            raise
        return path
    except OSError as error:
        raise NotAllowed(f"cannot read it ({error.strerror or error})",
                         "check the file's permissions") from None
    if not stat.S_ISREG(mode):
        raise NotAllowed("it is not a regular file (a folder, a device or a pipe)",
                         "name a file")
    named = _named.get()
    if named is not None:
        named.setdefault(str(path), path)
    return path


def digest(path: str | os.PathLike) -> str:
    """sha256 of a file's bytes; of a file over MAX_HASH_BYTES, 'size:N' (read no further)."""
    size = os.stat(path).st_size
    if size > MAX_HASH_BYTES:
        return f"size:{size}"
    sha = hashlib.sha256()
    with open(path, "rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            sha.update(block)
    return sha.hexdigest()


def digests(model_file: str, named: dict[str, Path]) -> dict[str, str]:
    """The model file (when it is a file) and every file it named: absolute path -> digest."""
    paths = [Path(model_file).resolve()] if Path(model_file).is_file() else []
    paths += [path for path in named.values() if path.is_file()]
    return {str(path): digest(path) for path in dict.fromkeys(paths)}


def read_bounded(path: str | os.PathLike, limit: int) -> bytes:
    """The bytes of a file, at most `limit` of them (TooLarge beyond)."""
    with open(path, "rb") as stream:
        data = stream.read(limit + 1)
    if len(data) > limit:
        raise TooLarge(len(data))
    return data
