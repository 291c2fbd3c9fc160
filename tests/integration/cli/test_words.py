"""Small things a user reads: the DOF line of `check` in words with its arithmetic, the repr of
a loaded model, `python -m casmech`, and the package's py.typed and player files shipped."""

import fnmatch
import re
import subprocess
import sys

import pytest
import tomllib

import casmech
from casmech.cli import main
from tests.conftest import MODELS, ROOT

PACKAGE = ROOT / "src" / "casmech"


@pytest.mark.parametrize("model, bodies, joint_rows, redundant", [
    ("four_bar.yaml", 3, 5 + 3 + 4 + 5 + 1, 0),  # revolute, spherical, universal, revolute, driver
    ("bricard.yaml", 5, 6 * 5, 1),  # six revolute joints, one row redundant (IFToMM A04)
])
def test_dof_in_words_adds_up(model, bodies, joint_rows, redundant, capsys):
    assert main(["check", str(MODELS / model)]) == 0
    out = capsys.readouterr().out
    first = re.search(r"degrees of freedom: (\d+) = (\d+) coordinates - rank (\d+) of the (\d+) "
                      r"constraint rows\n  \(6 per body - 1 per joint row: 6 x (\d+) - (\d+) = "
                      r"(-?\d+)(.*)\)", out)
    assert first, out
    dof, coordinates, rank, rows, nb, jr, count = map(int, first.groups()[:7])
    assert (coordinates, rows, nb, jr) == (7 * bodies, joint_rows + bodies, bodies, joint_rows)
    assert dof == coordinates - rank and count == 6 * bodies - joint_rows
    if redundant:
        assert f"{redundant} redundant row (below) repeats" in first[8]
        assert first[8].endswith(f"{count} + {redundant} = {dof}")
        assert out.count("  redundant: ") == redundant
    else:
        assert first[8] == "" and count == dof


def test_a_loaded_model_prints_in_one_line():
    model = casmech.load(MODELS / "four_bar.yaml", {"b": "2.5"})
    text = repr(model)
    assert "\n" not in text and len(text) < 300
    assert text.startswith("ResolvedModel('four_bar' from ")
    assert "3 bodies, 4 joints, 0 forces" in text and "b=2.5" in text
    assert "inverse_dynamics" in text and "(8 more)" in text  # 14 parameters, 6 shown


def test_python_dash_m_is_the_command(tmp_path):
    done = subprocess.run([sys.executable, "-m", "casmech", "check",
                           str(MODELS / "four_bar.yaml")], capture_output=True, text=True,
                          env={"PYTHONPATH": str(ROOT / "src"), "PATH": "/usr/bin:/bin",
                               "CASMECH_CACHE_DIR": str(tmp_path)}, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "degrees of freedom: 0" in done.stdout
    done = subprocess.run([sys.executable, "-m", "casmech", "run"], capture_output=True,
                          text=True, env={"PYTHONPATH": str(ROOT / "src"), "PATH": "/usr/bin",
                                          "CASMECH_CACHE_DIR": str(tmp_path)}, timeout=120)
    assert done.returncode == 2 and "needs a MODEL file" in done.stderr


def test_package_data_ships_py_typed_and_the_player():
    patterns = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"][
        "package-data"]["casmech"]
    assert (PACKAGE / "py.typed").is_file()
    wanted = ["py.typed", *(str(path.relative_to(PACKAGE))
                            for path in (PACKAGE / "io" / "player").iterdir()
                            if path.is_file())]
    assert {"io/player/three.min.js", "io/player/three.LICENSE"} <= set(wanted)
    for name in wanted:
        assert any(fnmatch.fnmatch(name, pattern) for pattern in patterns), name
    # the recipe that rebuilds three.min.js stays out of the package
    assert not any(fnmatch.fnmatch("io/player/vendor/build.sh", p) for p in patterns)
