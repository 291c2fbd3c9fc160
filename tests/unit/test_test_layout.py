"""The layout of tests/ (tests/README.md): every test file lives in tests/unit/, tests/integration/
or tests/validation/, under a folder named after a package of src/casmech; every collected test
carries exactly one of the markers `unit`, `integration`, `validation` (given by that folder in
tests/conftest.py); and `-m KIND` selects the tests of that folder and no other."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import KINDS, ROOT, TESTS, kind_of

SRC = ROOT / "src" / "casmech"
# Folders inside a kind's folder that hold data, not tests
DATA_FOLDERS = {"bad_models"}
# One small test file of each kind, collected together by the selection test
SAMPLES = {
    "unit": "tests/unit/runtime/test_memo.py",
    "integration": "tests/integration/test_docs.py",
    "validation": "tests/validation/runtime/test_linkages.py",
}


def all_test_files() -> list[Path]:
    return sorted(p for p in TESTS.rglob("test_*.py") if "__pycache__" not in p.parts)


def test_every_test_file_lives_in_one_kind_folder():
    files = all_test_files()
    assert len(files) > 150  # the glob found the suite
    outside = [str(p.relative_to(ROOT)) for p in files if kind_of(p) is None]
    assert not outside, f"test files outside the three kind folders: {outside}"


def test_subfolders_mirror_the_packages_of_src():
    packages = {p.name for p in SRC.iterdir() if (p / "__init__.py").is_file()}
    wrong = []
    for kind in KINDS:
        for folder in sorted((TESTS / kind).iterdir()):
            if folder.is_dir() and folder.name != "__pycache__" and folder.name not in DATA_FOLDERS:
                if folder.name not in packages:
                    wrong.append(f"tests/{kind}/{folder.name}")
                if not (folder / "__init__.py").is_file():
                    wrong.append(f"tests/{kind}/{folder.name} (no __init__.py)")
    assert not wrong, f"not named after a package of src/casmech: {wrong}"


def test_every_collected_test_has_exactly_one_kind(request):
    """Over the tests of this session (the whole suite when it runs whole)."""
    items = request.session.items
    assert request.node in items
    wrong = [(item.nodeid, kinds) for item in items
             if len(kinds := [k for k in KINDS if item.get_closest_marker(k)]) != 1]
    assert not wrong, wrong[:10]
    mine = [k for k in KINDS if request.node.get_closest_marker(k)]
    assert mine == ["unit"]


@pytest.mark.parametrize("kind", KINDS)
def test_marker_selects_its_folder(kind, tmp_path):
    """`pytest -m KIND` on one file of each kind collects the tests of KIND's file only."""
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1",
           "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(ROOT)])}
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider",
         "-m", kind, *SAMPLES.values()],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    collected = [line for line in result.stdout.splitlines() if "::" in line]
    assert collected, result.stdout
    files = {line.split("::")[0] for line in collected}
    assert files == {SAMPLES[kind]}, result.stdout
