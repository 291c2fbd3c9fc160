"""A model file's checked, resolved model kept in the compiled-model cache, so that a run of an
unchanged model reads it instead of validating and resolving the file again (no PyYAML,
pydantic or schema checks imported).

An entry is keyed by everything the load reads or depends on: the model file's bytes, the path
as given and where it resolves, the overrides (`--set`), the folders models may read from
(the model's own, $CASMECH_ALLOWED_DIRS, `--allow-dir`), casmech's version and source digest
(backends.cache: schema, core, elements...), Python's, NumPy's and the validating libraries'
files (pydantic, pydantic_core, PyYAML: their stamps) and the warning options. What the load
read besides the model file is checked on every use: each path it named resolves to the same
place, each file it found has the sha256 it had (ResolvedModel.sources), each it did not find
is still missing. Any difference is a miss: the model is loaded as without the cache and its
entry written again.

Only a load that succeeded and showed no warning is kept: a bad model's errors and a load's
warnings come from the load itself, every time. An entry is a folder in the cache folder's
FOLDER holding one pickle, listed in a manifest with its sha256, under the cache's trust rules
(backends.trust): the folders and files must be the user's and writable by no one else
(Untrusted, a usage error, otherwise), and the pickle's bytes must have the recorded sha256
(hashed as read, before they are unpickled), else the entry is discarded with a warning and
written again. A cache folder that cannot be used (not writable, not the user's) leaves the
load as without the cache, and the stage that needs the cache reports it.
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
import stat
import sys
import warnings
from collections.abc import Mapping
from contextlib import contextmanager
from importlib.util import find_spec
from pathlib import Path

import numpy as np

from casmech.backends import cache, stamps, trust
from casmech.backends.manifest import DIGESTS, FORMAT, MANIFEST
from casmech.core.version import VERSION
from casmech.errors import UsageError
from casmech.schema import files, load_model
from casmech.schema.resolved import ResolvedModel

KIND = "checked model"
FOLDER = "checked-models"  # the entries' folder in the cache folder (cache.entries lists libraries)
FILE = "model.pickle"
# the libraries that read and validate a model file: their installed files' stamps key it
VALIDATORS = ("pydantic", "pydantic_core", "yaml")


def load(path: str | Path, overrides: Mapping[str, str] | None = None) -> ResolvedModel:
    """The model at `path` with `overrides`, as schema.load_model gives it: the kept one when
    the cache holds it unchanged (module docstring), else loaded and kept."""
    overrides = dict(overrides or {})
    key = entry_key(path, overrides)
    if key is None:  # not a regular file that reads: the load says why
        return load_model(path, overrides)
    try:
        root = cache.prepared(cache.prepared() / FOLDER)
    except UsageError:  # reported by the stage that needs the cache, as without this entry
        return load_model(path, overrides)
    entry = root / key
    try:
        kept = _kept(entry)
    except trust.Untrusted:
        load_model(path, overrides)  # a bad model's errors come first, as without the cache
        raise
    if kept is not None:
        return kept
    model, asked, shown = _loaded(path, overrides)
    if not shown:
        _keep(root, entry, model, asked)
    return model


def entry_key(path: str | Path, overrides: Mapping[str, str]) -> str | None:
    """The cache key of a model file's checked model (None: not a regular file, or it does
    not read within the model file's size limit)."""
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return None
        data = files.read_bounded(path, files.MAX_MODEL_BYTES)
    except OSError:
        return None
    content = json.dumps({
        "kind": KIND, "format": FORMAT, "casmech": VERSION, "sources": cache.source_digest(),
        "python": sys.version, "numpy": np.__version__,
        "validators": [_stamp(name) for name in VALIDATORS], "warnings": sys.warnoptions,
        "model": hashlib.sha256(data).hexdigest(), "file": str(path),
        "resolved": str(Path(path).resolve()),
        "allowed": [str(folder) for folder in files.allowed_folders(str(path))],
        "overrides": sorted(overrides.items())})
    return "model-" + hashlib.sha256(content.encode()).hexdigest()[:32]


def _stamp(name: str) -> list | None:
    """An installed package's module file's stamp (backends.stamps: a reinstall writes new
    files), its path alone where it cannot be read; None: not installed."""
    spec = find_spec(name)
    if spec is None or not spec.origin:
        return None
    found = stamps.stamp([spec.origin])
    return [spec.origin] if found is None else found[0]


def _kept(entry: Path) -> ResolvedModel | None:
    """The entry's model when the entry is trusted and whole and what the model read is
    unchanged; None otherwise (a damaged entry discarded with a warning)."""
    if not cache.usable(entry):
        return None
    try:
        data = (entry / FILE).read_bytes()
        damaged = hashlib.sha256(data).hexdigest() != trust.verify(entry)[DIGESTS][FILE]
    except (OSError, KeyError, trust.Corrupt):
        damaged = True
    kept = None if damaged else _unpickled(data)
    if kept is None:
        warnings.warn(f"the compiled-model cache entry {entry} is damaged (its {FILE} does not "
                      "read as a checked model); building it again", stacklevel=3)
        cache.discard(entry)
        return None
    model, asked = kept
    return model if _unchanged(model, asked) else None


def _unpickled(data: bytes) -> tuple[ResolvedModel, dict[str, str]] | None:
    """(model, asked) from a verified entry's bytes; None when they do not make one (an entry
    written by another build whose classes differ)."""
    try:
        kept = pickle.loads(data)  # the user's own file, its sha256 checked
    except Exception:  # any failure to rebuild the entry makes it a miss
        return None
    if not (isinstance(kept, tuple) and len(kept) == 2 and isinstance(kept[0], ResolvedModel)
            and isinstance(kept[1], dict)):
        return None
    return kept


def _unchanged(model: ResolvedModel, asked: dict[str, str]) -> bool:
    """Whether every path the model's load named resolves where it did, and every file it
    found still has its digest (and every one it did not find is still missing)."""
    for joined, resolved in asked.items():
        if str(Path(joined).resolve()) != resolved:
            return False
        if resolved not in model.sources and os.path.exists(resolved):
            return False
    own = str(Path(model.file).resolve())
    for path, digest in model.sources.items():
        if path == own:  # the model file: its bytes are in the key
            continue
        try:
            if not os.path.isfile(path) or files.digest(path) != digest:
                return False
        except OSError:
            return False
    return True


def _loaded(path: str | Path, overrides: Mapping[str, str]
            ) -> tuple[ResolvedModel, dict[str, str], bool]:
    """(the model, the paths its load named -> where they resolved, whether the load showed a
    warning)."""
    with files.rooted(str(path)), _watching() as shown:
        model = load_model(path, overrides)
        asked = files.asked()
    return model, asked, bool(shown)


@contextmanager
def _watching():
    """Within the block, every warning shown is counted (and shown as it would be)."""
    shown: list[bool] = []
    show = warnings.showwarning

    def counted(*args, **kwargs):
        shown.append(True)
        return show(*args, **kwargs)

    warnings.showwarning = counted
    try:
        yield shown
    finally:
        warnings.showwarning = show


def _keep(root: Path, entry: Path, model: ResolvedModel, asked: dict[str, str]) -> None:
    """Write the entry (a stale one replaced), without the cache's lock: it is made in
    milliseconds, and processes racing to publish it write the same model (the rename keeps
    the entry whole). A model that does not pickle, or an entry that cannot be written, is
    not kept."""
    try:
        data = pickle.dumps((model, asked), protocol=pickle.HIGHEST_PROTOCOL)
    except (pickle.PicklingError, TypeError, AttributeError):
        return
    if entry.exists() or entry.is_symlink():
        cache.discard(entry)

    def write(directory: Path) -> None:
        (directory / FILE).write_bytes(data)
        (directory / MANIFEST).write_text(json.dumps({
            "format": FORMAT, "kind": KIND, "model": model.name, "casmech": VERSION,
            "library": FILE, "functions": [{"name": KIND, "library": FILE}],
            DIGESTS: {FILE: hashlib.sha256(data).hexdigest()}}, indent=1))

    try:
        cache.publish(root, entry.name, write)
    except OSError:
        pass  # the run goes on with the model it loaded
