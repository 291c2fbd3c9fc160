"""A file whose writes reach the disk in commits: what HDF5 writes through h5py's file-object
driver is held in memory until `commit`, which first reserves the space the file grows by
(os.posix_fallocate) and only then writes.

HDF5 does not survive a failed write: after a full disk or a file-size limit (EFBIG) its file
is left truncated and unreadable, and the library crashed the process (a segmentation fault)
when it closed the file. Through a StagedFile no write HDF5 makes ever fails: a commit that
cannot reserve its space writes nothing, so the file on disk stays as the last commit left it
(a readable HDF5 file holding the rows flushed before), `failure` holds the OSError and later
writes stay in memory until the file is dropped.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

UNSUPPORTED = (errno.EOPNOTSUPP, errno.EINVAL, errno.ENOSYS)  # posix_fallocate not available


class StagedFile:
    """The file-like object (read, readinto, write, seek, tell, truncate, flush) h5py.File
    takes; `commit()` writes what is staged (module docstring)."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_TRUNC, 0o666)
        self.size = 0  # bytes on disk (as of the last commit)
        self.length = 0  # bytes of the file as HDF5 sees it
        self.position = 0
        self.staged: list[tuple[int, bytes]] = []  # (offset, data) in the order written
        self.failure: OSError | None = None

    # -- the file object h5py calls
    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        base = {os.SEEK_SET: 0, os.SEEK_CUR: self.position, os.SEEK_END: self.length}[whence]
        self.position = base + offset
        return self.position

    def tell(self) -> int:
        return self.position

    def write(self, data) -> int:
        data = bytes(data)
        self.staged.append((self.position, data))
        self.position += len(data)
        self.length = max(self.length, self.position)
        return len(data)

    def readinto(self, buffer) -> int:
        view = memoryview(buffer).cast("B")
        data = self.read(len(view))
        view[:len(data)] = data
        return len(data)

    def read(self, size: int = -1) -> bytes:
        start = self.position
        end = self.length if size is None or size < 0 else min(self.length, start + size)
        if end <= start:
            return b""
        data = bytearray(os.pread(self.fd, end - start, start).ljust(end - start, b"\0"))
        for offset, chunk in self.staged:  # the staged writes over the disk's bytes
            low, high = max(offset, start), min(offset + len(chunk), end)
            if low < high:
                data[low - start:high - start] = chunk[low - offset:high - offset]
        self.position = end
        return bytes(data)

    def truncate(self, size: int | None = None) -> int:
        self.length = self.position if size is None else size
        self.staged = [(offset, chunk[:max(0, self.length - offset)])
                       for offset, chunk in self.staged if offset < self.length]
        return self.length

    def flush(self) -> None:
        """(h5py's flush reaches here; the commit is the caller's.)"""

    # -- the disk
    def commit(self) -> None:
        """Reserve the bytes the file grows by, then write everything staged; nothing is
        written when the reservation fails (then `failure`, and no commit again). Raises
        nothing: the caller reads `failure`."""
        if self.failure is not None:
            return
        try:
            if self.length > self.size:
                self._reserve(self.size, self.length - self.size)
            for offset, chunk in self.staged:
                os.pwrite(self.fd, chunk, offset)
            if self.length < self.size:
                os.ftruncate(self.fd, self.length)
        except OSError as error:
            self.failure = error
            return
        self.staged, self.size = [], self.length

    def _reserve(self, offset: int, length: int) -> None:
        """The blocks of [offset, offset + length) allocated; a file system that cannot
        reserve (no fallocate) is written without the reservation."""
        try:
            os.posix_fallocate(self.fd, offset, length)
        except OSError as error:
            if error.errno not in UNSUPPORTED:
                raise

    def close(self) -> None:
        os.close(self.fd)
