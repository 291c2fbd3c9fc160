"""The notebooks of examples/ run clean with nbclient (each cell's assertions included: the
energy a double pendulum keeps, a sweep equal to the same study by `set`, the fitted mass and
damping near the values the data were made with), from a temporary copy of examples/ beside
the repository's models, with Jupyter's and IPython's folders there too."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from tests.conftest import ROOT

NOTEBOOKS = sorted((ROOT / "examples").glob("*.ipynb"))


def test_there_are_three_notebooks():
    assert [p.name for p in NOTEBOOKS] == ["double_pendulum.ipynb", "estimate_pendulum.ipynb",
                                           "parameter_study.ipynb"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_runs_clean(path, tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    for variable in ("JUPYTER_RUNTIME_DIR", "JUPYTER_DATA_DIR", "IPYTHONDIR"):
        monkeypatch.setenv(variable, str(tmp_path / variable.lower()))
    monkeypatch.setenv("MPLBACKEND", "agg")
    (tmp_path / "models").symlink_to(ROOT / "models")
    folder = tmp_path / "examples"
    folder.mkdir()
    copy = Path(shutil.copy(path, folder))
    notebook = nbformat.read(copy, as_version=4)
    assert not any(cell.get("outputs") for cell in notebook.cells)  # committed cleared
    nbclient.NotebookClient(notebook, timeout=120, kernel_name="python3",
                            resources={"metadata": {"path": str(folder)}}).execute()
    errors = [output for cell in notebook.cells for output in cell.get("outputs", [])
              if output.output_type == "error"]
    assert not errors
    if path.stem == "double_pendulum":  # the player drew itself
        html = [output["data"]["text/html"] for output in notebook.cells[-1].outputs
                if "text/html" in output.get("data", {})]
        assert html and html[0].startswith("<iframe srcdoc=")
