"""output.staged.StagedFile: what is written reaches the disk only at a commit, reads see the
staged bytes over the disk's, and a commit that cannot reserve its space writes nothing."""

import errno
import os

import numpy as np

from casmech.io.hdf5 import h5py
from casmech.io.staged import StagedFile


def test_writes_reach_the_disk_at_a_commit_and_reads_see_them_before(tmp_path):
    staged = StagedFile(tmp_path / "f")
    staged.write(b"hello world")
    assert (tmp_path / "f").read_bytes() == b""  # staged only
    staged.seek(6)
    staged.write(b"there")
    staged.seek(0)
    assert staged.read() == b"hello there"
    staged.commit()
    assert (tmp_path / "f").read_bytes() == b"hello there"
    staged.seek(0, os.SEEK_END)
    staged.write(b"!")
    staged.seek(3)
    assert staged.read(4) == b"lo t"  # from the disk
    staged.truncate(5)
    staged.commit()
    staged.close()
    assert (tmp_path / "f").read_bytes() == b"hello"


def test_a_commit_that_cannot_reserve_writes_nothing(tmp_path, monkeypatch):
    staged = StagedFile(tmp_path / "f")
    staged.write(b"kept")
    staged.commit()
    staged.seek(0)
    staged.write(b"LOST and more")

    def full(fd, offset, length):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "posix_fallocate", full)
    staged.commit()
    assert staged.failure.errno == errno.ENOSPC
    staged.commit()  # no commit again
    staged.close()
    assert (tmp_path / "f").read_bytes() == b"kept"


def test_hdf5_through_it_reads_back(tmp_path):
    staged = StagedFile(tmp_path / "t.h5")
    with h5py().File(staged, "w") as handle:
        handle.create_dataset("x", data=np.arange(10.0))
    staged.commit()
    staged.close()
    with h5py().File(tmp_path / "t.h5", "r") as handle:
        np.testing.assert_array_equal(handle["x"][()], np.arange(10.0))  # bytes, not numerics
