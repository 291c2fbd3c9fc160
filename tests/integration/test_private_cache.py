"""The test suite never touches the user's caches (tests/conftest.py's private_caches), and
an interpreted run needs no code generation (no fcntl: Windows).

The first test runs a test of the suite that compiles models
(tests/validation/equations/test_limits.py, which once wrote into ~/.cache/casmech) in a
subprocess whose HOME is a temporary folder holding a user's cache with one entry, with
neither CASMECH_CACHE_DIR nor XDG_CACHE_HOME set, and compares that HOME's listing before and
after. As a control, a compile outside the suite in the same HOME does reach that cache folder,
so the listing would have seen a write."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from casmech.backends.codegen import available
from tests.conftest import ROOT

# one of its cases: a compile is what could write to the user's cache
COMPILING_TEST = ("tests/validation/equations/test_limits.py::"
                  "test_compiled_mode_equals_interpreted[slider]")


def listing(folder: Path) -> dict[str, tuple[int, int]]:
    return {str(p.relative_to(folder)): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in folder.rglob("*")}


def user_environment(home: Path) -> dict[str, str]:
    hidden = {"CASMECH_CACHE_DIR", "XDG_CACHE_HOME", "MPLCONFIGDIR"}
    return {**{k: v for k, v in os.environ.items() if k not in hidden}, "HOME": str(home),
            "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(ROOT)]),
            "OPENBLAS_NUM_THREADS": "1"}


@pytest.mark.skipif(not available(), reason="no C compiler")
def test_the_suite_leaves_the_users_cache_unchanged(tmp_path):
    home = tmp_path / "home"
    entry = home / ".cache" / "casmech" / "0123456789abcdef"
    entry.mkdir(parents=True)
    (entry / "manifest.json").write_text("{}")
    before = listing(home)
    environment = user_environment(home)
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           COMPILING_TEST], cwd=ROOT, env=environment, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert "passed" in done.stdout
    assert listing(home) == before

    # the control: outside the suite, a compile in this HOME builds into that very folder
    control = ("import casmech; casmech.compile(casmech.load('tests/helpers/codegen_model.yaml'), "
               "'compiled')")
    # built at -O0 (tests/conftest.py quick_builds): where it builds is the point, not how
    done = subprocess.run([sys.executable, "-c", control], cwd=ROOT,
                          env={**environment, "CASMECH_CFLAGS": "-O0"},
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    grown = set(listing(home)) - set(before)
    assert any(name.startswith(".cache/casmech/") and name.endswith("manifest.json")
               for name in grown), grown


def test_an_interpreted_dynamics_run_works_without_fcntl(tmp_path):
    """As on Windows, where fcntl does not exist: no code generation module
    (casmech.backends.*) is imported."""
    script = (
        "import sys; sys.modules['fcntl'] = None\n"
        "import casmech\n"
        "functions = casmech.compile(casmech.load('models/double_pendulum.yaml'), "
        "'interpreted')\n"
        "result = casmech.analyze(functions, t_end=0.5)\n"
        "loaded = sorted(m for m in sys.modules if m.startswith('casmech.backends.'))\n"
        "print(result.metadata['mode'], len(result), loaded)\n")
    done = subprocess.run([sys.executable, "-c", script], cwd=ROOT,
                          env={**user_environment(tmp_path), "CASMECH_CACHE_DIR":
                               str(tmp_path / "cache")},
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.split() == ["interpreted", "51", "[]"]  # rows t = 0, 0.01, ..., 0.5
