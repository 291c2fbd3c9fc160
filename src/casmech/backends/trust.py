"""What the compiled-model cache may load: only what this user built, unchanged.

Loading a shared library runs its code (its constructors run at load), so a library is loaded
only when
  - the cache folder, the entry's folder and every file in it are owned by the user running
    casmech and writable by no one else (group and others; no symbolic links): `Untrusted`,
    a usage error naming the path, otherwise; nothing is loaded and nothing is rebuilt over it;
  - the manifest reads as a casmech manifest and every library it lists has the sha256 the
    build recorded in it: `Corrupt` otherwise (a truncated, empty or edited library, a
    manifest cut short), which the cache answers by discarding the entry and building it again.
Each library is hashed once per process for as long as its file's identity and size and
modification time stay the same, and each entry's manifest read once for as long as none of
its files changes (`verify` keeps what it checked).

Ownership and mode bits are POSIX; on Windows (no os.getuid) the cache lives in the user's
own profile folder, whose access list is the user's, and only the sha256 check applies.
"""

from __future__ import annotations

import json
import os
import stat
import warnings
from pathlib import Path

from casmech.backends.manifest import DIGESTS, MANIFEST, sha256
from casmech.errors import UsageError

POSIX = hasattr(os, "getuid")


class Untrusted(UsageError):
    """A cache path someone other than the user could have written: refused."""


class Corrupt(UsageError):
    """An entry that is not what its build wrote (its reason as the message)."""


def _writers(mode: int) -> str:
    return " and ".join(who for who, bit in (("its group", stat.S_IWGRP),
                                              ("others", stat.S_IWOTH)) if mode & bit)


def problem(path: Path, status: os.stat_result | None = None) -> str | None:
    """Why the user should not trust `path` (not following a symbolic link), or None."""
    status = status or path.lstat()
    if stat.S_ISLNK(status.st_mode):
        return "is a symbolic link"
    if not POSIX:
        return None
    if status.st_uid != os.getuid():
        return f"is owned by uid {status.st_uid}, not by you (uid {os.getuid()})"
    if status.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return (f"is writable by {_writers(status.st_mode)} "
                f"(mode {stat.filemode(status.st_mode)})")
    return None


def refuse(path: Path, reason: str, remedy: str) -> Untrusted:
    return Untrusted(f"refusing the compiled-model cache: {path} {reason}; anyone who can "
                     f"write there could make casmech run their code. {remedy}")


def check_root(root: Path) -> None:
    """The cache folder itself: the user's (Untrusted otherwise), and made private (0700,
    with a warning) when others could write it."""
    status = root.stat()  # the folder a link names, when it is one
    reason = problem(root, status)
    if reason and POSIX and status.st_uid == os.getuid():
        warnings.warn(f"the compiled-model cache {root} {reason}: made it private (0700)",
                      stacklevel=4)
        root.chmod(0o700)
        reason = problem(root)
    if reason:
        raise refuse(root, reason, "Set CASMECH_CACHE_DIR to a folder of your own")


def private(directory: Path) -> None:
    """A new build's folder and files writable by the user alone (whatever the umask), so
    that verify accepts them."""
    for path in [directory, *directory.rglob("*")]:
        if not path.is_symlink():
            path.chmod(path.stat().st_mode & ~(stat.S_IWGRP | stat.S_IWOTH)
                       & (~0o077 if path.is_dir() else ~0))


def _files(directory: Path) -> list[tuple[Path, os.stat_result]]:
    found = []
    for path in [directory, *directory.rglob("*")]:
        found.append((path, path.lstat()))
    return found


def _manifest(directory: Path) -> dict:
    try:
        record = json.loads((directory / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise Corrupt(f"its {MANIFEST} does not read ({error})") from None
    if not isinstance(record, dict) or not isinstance(record.get("functions"), list) \
            or not isinstance(record.get("library"), (str, type(None))) \
            or not isinstance(record.get(DIGESTS), dict) \
            or not all(isinstance(e, dict) and isinstance(e.get("name"), str)
                       and isinstance(e.get("library"), (str, type(None)))
                       for e in record["functions"]):
        raise Corrupt(f"its {MANIFEST} is not one a casmech build writes")
    return record


def libraries(record: dict, default: str | None) -> set[str]:
    """The library files a manifest's functions load from."""
    return {entry.get("library") or record.get("library") or default
            for entry in record["functions"]}


_verified: dict[Path, tuple] = {}  # library -> (device, inode, size, mtime) when it was hashed
# entry -> (its files' stat results, its manifest) when it was verified: a run verifies an
# entry when it looks it up and again when it loads it, and a large model's manifest is
# megabytes of JSON
_manifests: dict[Path, tuple[tuple, dict]] = {}


def verify(directory: Path, default_library: str | None = None) -> dict:
    """The entry's manifest, once the entry is the user's (Untrusted otherwise) and every
    library it lists has its recorded sha256 (Corrupt otherwise); the manifest read before
    while none of the entry's files has changed since (their identities, sizes, times and
    modes)."""
    try:
        found = _files(directory)
    except OSError as error:  # a file removed while it was listed
        raise Corrupt(f"it changed while it was checked ({error.strerror})") from None
    for path, status in found:
        reason = problem(path, status)
        if reason:
            raise refuse(path, reason, "Remove it (`casmech cache clear`) and look into who "
                                       "wrote it")
    checked = tuple((str(path), status.st_dev, status.st_ino, status.st_size,
                      status.st_mtime_ns, status.st_ctime_ns, status.st_mode, status.st_uid)
                     for path, status in found)
    known = _manifests.get(directory)
    if known is not None and known[0] == checked:
        return known[1]
    record = _manifest(directory)
    recorded = record[DIGESTS]
    for name in sorted(libraries(record, default_library)):
        path = directory / str(name)
        if name not in recorded or Path(str(name)).name != name:
            raise Corrupt(f"its manifest records no sha256 for {name}")
        try:
            status = path.lstat()
        except OSError:
            raise Corrupt(f"{name} is missing") from None
        identity = (status.st_dev, status.st_ino, status.st_size, status.st_mtime_ns)
        if _verified.get(path) == identity:
            continue
        if not stat.S_ISREG(status.st_mode) or sha256(path) != recorded[name]:
            raise Corrupt(f"{name} is not the library its build wrote (sha256 differs)")
        _verified[path] = identity
    _manifests[directory] = (checked, record)
    return record
