"""Reading a file to import, with a bound on its size."""

from __future__ import annotations

from pathlib import Path

from casmech.errors import Diagnostic, ModelError, Source, UsageError

MAX_SOURCE_BYTES = 16 << 20  # an Adams deck, simEngine3D, URDF or MJCF file: tests' are 2-20 kB


def read_source(path: Path) -> str:
    """The text of a file to import, read up to MAX_SOURCE_BYTES (E006 beyond; undecodable
    bytes replaced)."""
    from casmech.schema import files

    try:
        data = files.read_bounded(path, MAX_SOURCE_BYTES)
    except files.TooLarge as error:
        raise ModelError([Diagnostic("E006", "", f"the file is larger than "
                                     f"{MAX_SOURCE_BYTES >> 20} MiB ({error.size} bytes or "
                                     "more)", Source(str(path), 1, 1))]) from None
    except OSError as error:
        raise UsageError(f"cannot read {path}: {error.strerror or error}") from None
    return data.decode("utf-8", errors="replace")
