"""The build cache: one directory per key, published atomically.

Key: the model's content (its text, the texts of the component files it was composed from, the
data of every table it reads, and its resolved parameters, so --set overrides count; a
parametric library's key has the model's structure instead of the parameter values,
codegen.parametric), the
casmech version and a digest of its compiler sources, the CasADi version, the C compiler and its
flags. A build happens in a private temporary directory under the cache and is published with
one rename; a lock file (filelock: fcntl on POSIX, msvcrt on Windows) makes a second process
wait for the first instead of building the same key again, and the rename alone keeps the cache
whole should the lock not hold (NFS).

The cache folder is $CASMECH_CACHE_DIR, else the platform's user cache folder (platformdirs:
~/.cache/casmech on Linux, ~/Library/Caches/casmech on macOS, %LOCALAPPDATA%/casmech/Cache on
Windows), created 0700. An entry is loaded only after codegen.trust has found it the user's and
unchanged; a corrupt one (a library cut short or edited, a manifest that does not read) is
discarded with a warning and built again, never loaded.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
import warnings
from collections.abc import Callable, Mapping
from dataclasses import fields, is_dataclass
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np

from casmech.backends import stamps, trust
from casmech.backends.build import LIBRARY
from casmech.backends.folder import ENVIRONMENT, cache_dir  # noqa: F401 (cache.ENVIRONMENT)
from casmech.backends.manifest import FORMAT, MANIFEST
from casmech.core.last_call import last_call
from casmech.core.version import VERSION
from casmech.errors import Source, UsageError
from casmech.formulations import residuals
from casmech.schema.resolved import ResolvedModel
from casmech.schema.tables import TableExpr

PACKAGE = Path(__file__).resolve().parents[1]
# what the generated code depends on: these packages (with their subpackages) and the runtime
# modules that build graphs compiled under a key of their own (backends.library.compile_keyed:
# the joint system's library, which functions runtime.joint_dynamics.keyed_system compiles or
# keeps; the loops' projected ODE; the singular-pose check's log-determinants)
SOURCE_PACKAGES = ("core", "numerics", "elements", "schema", "model", "equations", "formulations",
                   "backends")
BYTECODE = "__pycache__"
SOURCE_MODULES = ("runtime/joint_dynamics.py", "runtime/projected_loops.py",
                  "runtime/singular_poses.py")


def _sources() -> list[tuple[str, str]]:
    """(name, path) of every source file source_digest reads, in its order: each package's
    .py files below it (the order of their paths' parts), then SOURCE_MODULES."""
    found, start = [], len(str(PACKAGE)) + 1
    for package in SOURCE_PACKAGES:
        paths = _python_files(str(PACKAGE / package))
        named = [(path[start:].replace(os.sep, "/"), path) for path in paths]
        found += sorted(named, key=lambda item: item[0].split("/"))
    return found + [(Path(name).name, str(PACKAGE / name)) for name in SOURCE_MODULES]


def _python_files(folder: str) -> list[str]:
    """The .py files below `folder` (a link to a folder listed by os.walk, not followed), the
    bytecode folders (BYTECODE: no source in them) not entered: a warm run reads this on every
    start."""
    found = []
    for root, folders, files in os.walk(folder):
        folders[:] = [name for name in folders if name != BYTECODE]
        found += [os.path.join(root, name) for name in files if name.endswith(".py")]
    return found


def _hexdigest(text: str) -> bool:
    return len(text) == 64 and all(c in "0123456789abcdef" for c in text)


@lru_cache(maxsize=1)
def source_digest() -> str:
    """sha256 of casmech's own sources that shape the generated code (an edited compiler in a
    development install must not reuse stale builds under the same version number); read
    once for as long as no file changes (backends.stamps, in the cache folder when it
    exists)."""
    sources = _sources()

    def digest() -> str:
        found = hashlib.sha256()
        for name, path in sources:
            with open(path, "rb") as file:
                found.update(name.encode() + b"\0" + file.read())
        return found.hexdigest()

    return stamps.remembered("casmech sources", [path for _, path in sources], digest,
                             _hexdigest, cache_dir())


# what holds no table: skipped without a call (an error's Source is a file, line and column)
LEAVES = (str, bytes, int, float, complex, bool, type(None), np.ndarray, Source)
_LEAF_TYPES = frozenset(LEAVES)
_FIELDS: dict[type, tuple[str, ...] | None] = {}  # a class -> its dataclass fields' names


def _tables(value, found: list, seen: set) -> list:
    """Every table (schema.tables.TableExpr) reachable from a resolved model's fields, in a
    fixed order: a CSV's content lives only there, not in any text."""
    if id(value) in seen or isinstance(value, LEAVES):
        return found
    seen.add(id(value))
    if isinstance(value, TableExpr):
        found.append(value)
        return found
    kind = type(value)
    if kind not in _FIELDS:
        _FIELDS[kind] = tuple(item.name for item in fields(value)) \
            if is_dataclass(value) else None
    names = _FIELDS[kind]
    if names is not None:
        items = [getattr(value, name) for name in names]
    elif isinstance(value, Mapping):
        items = value.values()
    elif isinstance(value, (tuple, list)):
        items = value
    else:
        return found
    for item in items:
        if type(item) not in _LEAF_TYPES:
            _tables(item, found, seen)
    return found


# the last model digested, with its digests (by `values`): a run keys its library twice
# (codegen.auto_choice looks it up, then codegen.compiled loads it); the model is a frozen
# record
_digests = last_call(lambda model: {})


def model_digest(model: ResolvedModel, values: bool = True) -> str:
    """sha256 of everything the generated code of a model depends on; without `values`, of
    everything but its parameter values (a parametric library takes them as an input). The
    same again for the model digested last."""
    known = _digests(model)
    if values not in known:
        known[values] = _digest(model, values)
    return known[values]


def _digest(model: ResolvedModel, values: bool) -> str:
    parameters = {k: float(v) for k, v in sorted(model.parameters.items())} if values else {}
    digest = hashlib.sha256(json.dumps({
        "text": model.text, "files": dict(sorted(model.files.items())),
        "parameters": parameters}).encode())
    table_digest(model, digest)
    return digest.hexdigest()


def table_digest(value, digest) -> None:
    """Update the hashlib `digest` with every table reachable from `value` (a resolved model,
    a ModelIR): its text and its polynomial's data."""
    for table in _tables(value, [], set()):
        polynomial = table.polynomial
        digest.update(json.dumps([table.text, polynomial.periodic, list(polynomial.slopes),
                                  polynomial.increment]).encode())
        digest.update(np.ascontiguousarray(polynomial.breaks, float).tobytes())
        digest.update(np.ascontiguousarray(polynomial.coefficients, float).tobytes())


def key(model_hash: str, compiler: str, flags, dae: bool = False,
        names: tuple[str, ...] | None = None) -> str:
    """The mapped library's cache key; `dae`: with the residuals the registered formulations
    compile (formulations.residuals.library_key); `names`: of the bundle's functions only
    these (None: all)."""
    content = json.dumps({"format": FORMAT, "model": model_hash, "casmech": VERSION,
                          "sources": source_digest(), "casadi": ca.__version__,
                          "compiler": compiler, "flags": list(flags),
                          "dae": residuals.library_key() if dae else False,
                          "functions": None if names is None else list(names)})
    return hashlib.sha256(content.encode()).hexdigest()[:32]


def prepared(root: Path | None = None) -> Path:
    """The cache folder, created 0700 where missing, checked writable and the user's alone
    (codegen.trust: a usage error otherwise)."""
    root = root or cache_dir()
    try:
        root.mkdir(mode=0o700, parents=True, exist_ok=True)
        probe = tempfile.TemporaryFile(dir=root)
        probe.close()
    except OSError as error:
        raise UsageError(f"the compiled-model cache {root} is not writable ({error.strerror}); "
                         f"set {ENVIRONMENT} to a writable directory") from None
    trust.check_root(root)
    return root


def usable(entry: Path) -> bool:
    """Whether a published entry is there and may be loaded (codegen.trust.verify). A corrupt
    one is removed with a warning (False: build it again); one someone else could have
    written is refused (trust.Untrusted)."""
    if not entry.exists() and not entry.is_symlink():
        return False
    try:
        trust.verify(entry, LIBRARY)
        return True
    except trust.Corrupt as reason:
        warnings.warn(f"the compiled-model cache entry {entry} is damaged ({reason}); "
                      "building it again", stacklevel=3)
    discard(entry)
    return False


def discard(entry: Path) -> None:
    """Move an entry aside (one rename, so no reader sees half of it) and remove it."""
    aside = Path(tempfile.mkdtemp(prefix=f".{entry.name}.discarded.", dir=entry.parent))
    try:
        os.replace(entry, aside / "entry")
    except OSError:
        pass  # another process moved it first
    shutil.rmtree(aside, ignore_errors=True)


def lookup(entry_key: str, build: Callable[[Path], None], root: Path | None = None
           ) -> tuple[Path, bool]:
    """The cache directory of a key, building it with build(temporary_dir) when missing or
    damaged; returns (directory, hit). A hit is verified (codegen.trust) before it is
    returned."""
    root = prepared(root)
    final = root / entry_key
    if usable(final):
        return final, True
    from filelock import FileLock  # imported on a miss only: a hit takes no lock

    with FileLock(root / f"{entry_key}.lock"):
        if usable(final):
            return final, True
        publish(root, entry_key, build)
    trust.verify(final, LIBRARY)
    return final, False


def publish(root: Path, entry_key: str, build: Callable[[Path], None]) -> None:
    """build(temporary_dir) in a private temporary directory of `root`, published as the
    key's entry by one rename (kept out when another process published first)."""
    final = root / entry_key
    temporary = Path(tempfile.mkdtemp(prefix=f".{entry_key}.", dir=root))
    try:
        build(temporary)
        trust.private(temporary)
        os.replace(temporary, final)  # atomic; fails if another process published first
    except OSError:
        if not (final / MANIFEST).is_file():
            raise
    finally:
        shutil.rmtree(temporary, ignore_errors=True)


def entries(root: Path | None = None) -> list[Path]:
    root = root or cache_dir()
    return sorted(p for p in root.glob("*") if p.is_dir() and (p / MANIFEST).is_file()) \
        if root.is_dir() else []


def unfinished(root: Path | None = None) -> list[Path]:
    """Hidden temporary build folders: builds in progress, or left by a killed one."""
    root = root or cache_dir()
    return sorted(p for p in root.glob(".*") if p.is_dir()) if root.is_dir() else []


def size(path: Path) -> int:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


def clear(root: Path | None = None) -> int:
    """Remove every entry (and stale temporary directories and locks); the bytes freed."""
    root = root or cache_dir()
    if not root.is_dir():
        return 0
    freed = 0
    for path in root.iterdir():
        if path.is_dir():
            freed += size(path)
            shutil.rmtree(path, ignore_errors=True)
        elif path.suffix == ".lock":
            path.unlink(missing_ok=True)
    return freed
