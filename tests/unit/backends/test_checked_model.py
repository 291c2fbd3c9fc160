"""backends.checked_model: a model file's checked model kept in the cache, used while nothing
its load read or depends on changed, under the cache's trust rules."""

import hashlib
import json
import pickle
import shutil
import warnings
from dataclasses import fields, is_dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from casmech.backends import cache, checked_model, trust
from casmech.backends.manifest import DIGESTS, MANIFEST
from casmech.errors import ModelError
from casmech.schema import load_model
from tests.conftest import MODELS


@pytest.fixture
def root(tmp_path, monkeypatch):
    """A cache folder of the test's own, and a count of the loads that validate a file."""
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("CASMECH_ALLOWED_DIRS", raising=False)
    loads = []

    def counted(*args, **kwargs):
        loads.append(args[0])
        return load_model(*args, **kwargs)

    monkeypatch.setattr(checked_model, "load_model", counted)
    return SimpleNamespace(folder=tmp_path / "cache", loads=loads)


def _models(tmp_path) -> Path:
    """The gallery's quadruped (a component file) and table driver (a CSV table), copied."""
    folder = tmp_path / "models"
    shutil.copytree(MODELS / "components", folder / "components")
    for name in ("quadruped_legs.yaml", "table_driver.yaml", "table_driver_profile.csv",
                 "pendulum.yaml"):
        shutil.copy(MODELS / name, folder / name)
    return folder


def _entries(root) -> list[Path]:
    folder = root.folder / checked_model.FOLDER
    return sorted(p for p in folder.iterdir() if p.is_dir()) if folder.is_dir() else []


def same(a, b) -> bool:
    """Equal field by field, arrays bit for bit (with their dtypes)."""
    if type(a) is not type(b):
        return False
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and np.array_equal(a, b)
    if is_dataclass(a):
        return all(same(getattr(a, f.name), getattr(b, f.name)) for f in fields(a))
    if isinstance(a, dict) or hasattr(a, "keys"):
        return list(a.keys()) == list(b.keys()) and all(same(a[k], b[k]) for k in a)
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if hasattr(a, "__dict__") and not callable(a):
        return same(vars(a), vars(b))
    return a == b


@pytest.mark.parametrize("name", ["quadruped_legs.yaml", "table_driver.yaml"])
def test_a_second_load_is_the_kept_model_equal_to_a_fresh_one(root, tmp_path, name):
    path = _models(tmp_path) / name
    first = checked_model.load(path, {})
    again = checked_model.load(path, {})
    assert len(root.loads) == 1  # the second came from the entry
    assert len(_entries(root)) == 1
    assert same(again, load_model(path)) and same(first, again)
    assert cache.entries(root.folder) == []  # not listed among the compiled libraries


@pytest.mark.parametrize("edit", ["model", "component", "table", "overrides", "sources",
                                  "allowed"])
def test_what_the_load_read_or_depends_on_changed_is_a_miss(root, tmp_path, monkeypatch,
                                                               edit):
    folder = _models(tmp_path)
    name = "table_driver.yaml" if edit == "table" else "quadruped_legs.yaml"
    path = folder / name
    checked_model.load(path, {})
    given = {}
    if edit == "model":
        path.write_text(path.read_text().replace("mt: 8.0", "mt: 9.0"))
    elif edit == "component":
        leg = folder / "components" / "leg.yaml"
        leg.write_text(leg.read_text() + "\n# edited\n")
    elif edit == "table":
        table = folder / "table_driver_profile.csv"
        table.write_text(table.read_text() + "\n")
    elif edit == "overrides":
        given = {"mt": "9"}
    elif edit == "sources":
        monkeypatch.setattr(cache, "source_digest", lambda: "0" * 64)
    else:
        monkeypatch.setenv("CASMECH_ALLOWED_DIRS", str(tmp_path))
    again = checked_model.load(path, given)
    assert len(root.loads) == 2  # loaded again
    assert same(again, load_model(path, given))
    checked_model.load(path, given)
    assert len(root.loads) == 2  # and kept again


def test_a_named_file_that_appears_is_a_miss(root, tmp_path):
    """A mesh named but missing at the first load (no error: `casmech animate` reads it) is
    among the model's sources once it exists."""
    folder = _models(tmp_path)
    path = folder / "pendulum.yaml"
    path.write_text(path.read_text().replace("{sphere: r}", "{mesh: ball.stl}"))
    assert len(checked_model.load(path, {}).sources) == 1
    (folder / "ball.stl").write_text("solid ball\nendsolid ball\n")
    again = checked_model.load(path, {})
    assert len(root.loads) == 2 and str(folder / "ball.stl") in again.sources


def test_a_bad_model_is_never_kept(root, tmp_path):
    path = _models(tmp_path) / "pendulum.yaml"
    path.write_text(path.read_text().replace("mass: m", "mass: -m"))
    for _ in range(2):
        with pytest.raises(ModelError) as error:
            checked_model.load(path, {})
        assert "mass" in str(error.value)
    assert len(root.loads) == 2 and _entries(root) == []


def test_a_load_that_warned_is_not_kept(root, tmp_path, monkeypatch):
    path = _models(tmp_path) / "pendulum.yaml"

    def warning(*args, **kwargs):
        root.loads.append(args[0])
        warnings.warn("a warning of the load", UserWarning, stacklevel=1)
        return load_model(*args, **kwargs)

    monkeypatch.setattr(checked_model, "load_model", warning)
    for _ in range(2):
        with pytest.warns(UserWarning, match="a warning of the load"):
            checked_model.load(path, {})
    assert len(root.loads) == 2 and _entries(root) == []


@pytest.mark.parametrize("damage", ["cut", "replaced", "swapped after the check",
                                    "not a model"])
def test_a_damaged_entry_is_discarded_and_written_again(root, tmp_path, monkeypatch, damage):
    path = _models(tmp_path) / "pendulum.yaml"
    expected = checked_model.load(path, {})
    (entry,) = _entries(root)
    kept = entry / checked_model.FILE
    if damage == "cut":  # its sha256 no longer the manifest's
        kept.write_bytes(kept.read_bytes()[:100])
    elif damage.startswith(("replaced", "swapped")):  # another model, the first one's sha256
        other = load_model(MODELS / "double_pendulum.yaml")
        kept.write_bytes(pickle.dumps((other, {})))
        if damage.startswith("swapped"):  # after the entry's check: the bytes read are hashed
            monkeypatch.setattr(cache, "usable", lambda entry: entry.exists())
    else:  # the recorded sha256, but not a checked model: refused after the check
        data = pickle.dumps({"not": "a model"})
        kept.write_bytes(data)
        record = json.loads((entry / MANIFEST).read_text())
        record[DIGESTS][checked_model.FILE] = hashlib.sha256(data).hexdigest()
        (entry / MANIFEST).write_text(json.dumps(record))
    with pytest.warns(UserWarning, match="damaged"):
        again = checked_model.load(path, {})
    assert len(root.loads) == 2 and same(again, expected)
    checked_model.load(path, {})
    assert len(root.loads) == 2  # written again whole


def test_an_entry_others_could_write_is_refused(root, tmp_path):
    path = _models(tmp_path) / "pendulum.yaml"
    checked_model.load(path, {})
    (entry,) = _entries(root)
    entry.chmod(0o775)
    with pytest.raises(trust.Untrusted, match="writable by its group"):
        checked_model.load(path, {})
    entry.chmod(0o700)


def test_an_unusable_cache_folder_leaves_the_load_as_without_it(root, tmp_path):
    """The cache's own errors are reported where a stage uses the cache (an interpreted run
    may use none)."""
    path = _models(tmp_path) / "pendulum.yaml"
    root.folder.write_text("a file, not a folder")
    for _ in range(2):
        checked_model.load(path, {})
    assert len(root.loads) == 2


def test_the_key_is_none_for_what_is_not_a_regular_file(tmp_path):
    assert checked_model.entry_key(tmp_path, {}) is None
    assert checked_model.entry_key(tmp_path / "missing.yaml", {}) is None
