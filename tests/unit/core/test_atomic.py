"""core.atomic: a write is renamed into place when it completes and leaves nothing behind when
it fails (the earlier file stays as it was)."""

import pytest

from casmech.core.atomic import atomic


@pytest.mark.parametrize("mode, data", [("w", "new\n"), ("wb", b"new\n")])
def test_complete_writes_replace_failed_ones_leave_the_old_file(tmp_path, mode, data):
    target = tmp_path / "out" / "file"
    with atomic(target, mode) as handle:
        handle.write(data)
    with pytest.raises(RuntimeError), atomic(target, mode) as handle:
        handle.write(data * 2)
        raise RuntimeError("writer failed")
    assert [p.name for p in target.parent.iterdir()] == ["file"]
    assert target.read_bytes() == b"new\n"
