"""Files written atomically: under a temporary name of their own beside the target (two runs
into one folder do not share it), renamed to the target once complete, removed if writing
fails, so a reader never sees a half-written file."""

from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def replaced(path: Path):
    """The temporary path to write (for writers that open files by name, as h5py does)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    descriptor, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.",
                                             suffix=".tmp")
    os.close(descriptor)
    try:
        yield Path(temporary)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


@contextmanager
def atomic(path: Path, mode: str = "w", **options):
    """The open temporary file (`mode` and `options` as for open)."""
    with replaced(path) as temporary, open(temporary, mode, **options) as handle:
        yield handle
