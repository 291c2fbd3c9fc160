"""Shared fixtures: paths to the example models, running a model through the API, seeded
generators, and the markers `unit`, `integration` and `validation` given by folder
(tests/README.md)."""

import os
import re
import shutil
import tempfile
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.runtime.buffers import BufferedCall, ColumnCall

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
TESTS = ROOT / "tests"
# The kind of a test is the first folder under tests/ that holds it; its marker has that name
KINDS = ("unit", "integration", "validation")
SEEDS = [0, 1, 2, 3, 4]


def kind_of(path) -> str | None:
    """The kind folder ("unit", "integration", "validation") holding a test file, or None."""
    parts = Path(path).resolve().relative_to(TESTS).parts
    return parts[0] if len(parts) > 1 and parts[0] in KINDS else None


CACHE_VARIABLES = ("CASMECH_CACHE_DIR", "XDG_CACHE_HOME", "MPLCONFIGDIR")
_SESSION_CACHES: list[str] = []


def pytest_configure(config):
    """Before any fixture (a module- or session-scoped one is made before the per-test
    private_caches below): the caches point into a temporary folder of the session's and no
    library is built behind a run, so that nothing a test does writes to the user's caches."""
    folder = tempfile.mkdtemp(prefix="casmech-tests-")
    _SESSION_CACHES.append(folder)
    for name in CACHE_VARIABLES:
        os.environ[name] = str(Path(folder) / name.lower())
    os.environ["CASMECH_BACKGROUND_BUILD"] = "0"


def pytest_unconfigure(config):
    for folder in _SESSION_CACHES:
        shutil.rmtree(folder, ignore_errors=True)


def pytest_collection_modifyitems(config, items):
    """Mark every test with the kind of the folder it lives in (`-m unit`, `-m validation`...);
    tests/unit/test_test_layout.py fails for a test outside the three folders."""
    for item in items:
        kind = kind_of(item.path)
        if kind is not None:
            item.add_marker(getattr(pytest.mark, kind))


class Table:
    """Results table with column access by contract name: table["bar.x"]."""

    def __init__(self, names, values):
        self.names, self.values = list(names), np.asarray(values)

    def __getitem__(self, name):
        return self.values[:, self.names.index(name)]


def count_calls(monkeypatch) -> list[str]:
    """The names of every casadi.Function evaluation made from Python from now on (symbolic,
    numeric, or buffered: runtime.buffers), with a mapped function's row count left out
    (mapN_f -> map_f) and a ColumnCall's blocks counted as one call of its function, for
    tests that no analysis calls CasADi once per row."""
    calls, inside = [], []
    call, buffered, columns = ca.Function.call, BufferedCall.__call__, ColumnCall.__call__

    def name(function) -> str:
        return re.sub(r"^map\d+_", "map_", function.name())

    def counting(self, *args, **kwargs):
        if not inside:
            calls.append(name(self))
        return call(self, *args, **kwargs)

    def counting_buffered(self, *args):
        if not inside:
            calls.append(name(self.function))
        return buffered(self, *args)

    def counting_columns(self, *args):
        calls.append(f"map_{self.function.name()}")
        inside.append(self)
        try:
            return columns(self, *args)
        finally:
            inside.pop()

    monkeypatch.setattr(ca.Function, "call", counting)  # Function.__call__ goes through call
    monkeypatch.setattr(BufferedCall, "__call__", counting_buffered)
    monkeypatch.setattr(ColumnCall, "__call__", counting_columns)
    return calls


def run_model(path, **kwargs):
    functions = casmech.compile(casmech.load(path))
    result = casmech.analyze(functions, **kwargs)
    return functions, Table(*casmech.results_table(functions, result))


@pytest.fixture(scope="session")
def session_cache(tmp_path_factory) -> Path:
    """The compiled-model cache of the whole test session (a private temporary folder)."""
    return tmp_path_factory.mktemp("session_cache")


@pytest.fixture(autouse=True)
def private_caches(session_cache, monkeypatch) -> Path:
    """No test reads or writes the user's caches: casmech's compiled-model cache
    (CASMECH_CACHE_DIR; subprocesses inherit it) and the folders derived from HOME that a
    library may cache into (XDG_CACHE_HOME: platformdirs' user cache folder on Linux;
    MPLCONFIGDIR: matplotlib's font cache) point into the session's temporary folder.
    tests/integration/test_private_cache.py proves it. No library is built behind a run
    (CASMECH_BACKGROUND_BUILD=0: a detached build would outlive the test that started it);
    tests/integration/backends/test_background.py turns it on."""
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(session_cache / "casmech"))
    monkeypatch.setenv("CASMECH_BACKGROUND_BUILD", "0")
    monkeypatch.setenv("XDG_CACHE_HOME", str(session_cache / "xdg"))
    monkeypatch.setenv("MPLCONFIGDIR", str(session_cache / "matplotlib"))
    return session_cache / "casmech"


@pytest.fixture
def quick_builds(monkeypatch) -> None:
    """C built at -O0 (CASMECH_CFLAGS, what the CLI and casmech.compile build with): for a test
    of what compiled code computes, not of its speed; gcc's quickest build, as the backends'
    tests build (tests/helpers/codegen.py)."""
    monkeypatch.setenv("CASMECH_CFLAGS", "-O0")


@pytest.fixture(scope="session")
def models_dir():
    return MODELS


@pytest.fixture(autouse=True, scope="session")
def mujoco_warnings_kept():
    """MuJoCo writes its warnings to MUJOCO_LOG.TXT in the working directory; in the tests
    they go to this list instead, so the suite writes nothing outside temporary folders."""
    try:
        import mujoco
    except ImportError:
        yield []
        return
    seen: list[str] = []
    mujoco.set_mju_user_warning(seen.append)
    yield seen


@pytest.fixture(params=SEEDS, ids=lambda s: f"seed{s}")
def rng(request) -> np.random.Generator:
    """A seeded generator; every test using it runs once per seed."""
    return np.random.default_rng(request.param)
