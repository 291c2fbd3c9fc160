"""--resume adds runs to an earlier study only when it is the same study (study.sweep.
same_study): the model text, the files it reads, the --set overrides and the analysis
settings recorded in the earlier part's metadata.json; otherwise the rows of two studies would
mix in one sweep.csv (journal.read checks only the columns and each row's parameter values).
The earlier metadata.json is read as untrusted input: a key it lacks is not compared."""

import json
import shutil

import pandas as pd
import pytest

from casmech import cli
from tests.helpers.study import SPRING_MASS

STUDY = ["--samples", "4", "--normal", "m=2,0.1", "--seed", "2", "--keep", "max(block.z)",
         "--workers", "0", "--t-end", "0.05", "--mode", "interpreted"]


@pytest.fixture
def model(tmp_path):
    """The spring-mass study model, copied where a test may edit it."""
    path = tmp_path / "spring_mass.yaml"
    shutil.copy(SPRING_MASS, path)
    return path


def sweep(model, out, *extra) -> int:
    return cli.main(["sweep", str(model), *STUDY, "--out", str(out), *extra])


def cut(out, kept: int) -> None:
    """sweep.csv as a kill after `kept` runs leaves it (header and those rows)."""
    lines = (out / "sweep.csv").read_text().splitlines(keepends=True)
    (out / "sweep.csv").write_text("".join(lines[:1 + kept]))


def rows(out) -> pd.DataFrame:
    return pd.read_csv(out / "sweep.csv").drop(columns="wall_s")


@pytest.mark.parametrize("edit, extra, said", [
    (lambda text: text.replace("k: 200.0", "k: 250.0"), (), "other model file"),
    (lambda text: text + "# a comment changes the file's text too\n", (), "other model file"),
    (None, ("--rtol", "1e-6"), "other analysis settings"),
    (None, ("--set", "k=250"), "other --set overrides"),
])
def test_another_study_is_not_resumed(model, tmp_path, capsys, edit, extra, said):
    out = tmp_path / "study"
    assert sweep(model, out) == 0
    cut(out, 2)
    if edit is not None:
        model.write_text(edit(model.read_text()))
    capsys.readouterr()
    assert sweep(model, out, "--resume", *extra) == 2
    err = capsys.readouterr().err
    assert said in err and "--resume" in err and "Traceback" not in err
    assert len(pd.read_csv(out / "sweep.csv")) == 2  # nothing ran, nothing was rewritten


def test_the_same_study_resumes_to_the_whole_studys_rows(model, tmp_path):
    """The control: unchanged, the resumed study's rows equal an uninterrupted one's."""
    part, whole = tmp_path / "part", tmp_path / "whole"
    assert sweep(model, part, "--set", "k=250") == 0
    cut(part, 2)
    assert sweep(model, part, "--resume", "--set", "k=250") == 0
    assert sweep(model, whole, "--set", "k=250") == 0
    pd.testing.assert_frame_equal(rows(part), rows(whole))  # the same runs, bit for bit


@pytest.mark.parametrize("change, refused", [
    ({"model": "not a dict"}, True),
    ({"model": {"sha256": ["a", "list"]}}, True),
    ({"files": {"mesh.stl": "\u001b[2J"}}, True),
    ({"analysis": None}, True),
    ({"model": None, "drop": ("files", "overrides", "analysis")}, True),
    ({"drop": ("model", "files", "overrides", "analysis")}, False),  # nothing left to compare
])
def test_a_damaged_earlier_metadata_is_compared_not_trusted(model, tmp_path, capsys, change,
                                                            refused):
    out = tmp_path / "study"
    assert sweep(model, out) == 0
    cut(out, 2)
    metadata = json.loads((out / "metadata.json").read_text())
    for key in change.pop("drop", ()):
        del metadata[key]
    metadata.update(change)
    (out / "metadata.json").write_text(json.dumps(metadata))
    capsys.readouterr()
    assert sweep(model, out, "--resume") == (2 if refused else 0)
    err = capsys.readouterr().err
    assert "Traceback" not in err and "\x1b" not in err
    assert len(pd.read_csv(out / "sweep.csv")) == (2 if refused else 4)
