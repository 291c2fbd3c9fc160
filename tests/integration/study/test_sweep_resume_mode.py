"""A resumed study runs in the mode its earlier part ran in (issue 36): under method auto the
mode picks the integrator (docs/decisions/method-auto.md), so a study started interpreted and
resumed once its library is cached would otherwise mix rows that differ within the tolerance.

A study of the spring-mass model (4 runs, short) starts under auto with an empty cache
(interpreted), loses its last runs as a kill would, the library is then cached (auto would now
pick compiled: the control) and --resume completes it: every row equals a fresh interpreted
study's bit for bit, while a compiled study's rows differ. An explicit --mode wins and says so;
metadata.json's mode is read as untrusted input; its top-level mode is the runs'."""

import json

import pandas as pd
import pytest

import casmech
from casmech import cli
from casmech.study.sweep import study_mode
from tests.helpers.study import SPRING_MASS

STUDY = ["--samples", "4", "--normal", "m=2,0.1", "--seed", "2", "--keep", "max(block.z)",
         "--keep", "final(block.vz)", "--workers", "0", "--t-end", "0.05"]


@pytest.fixture
def uncached(tmp_path, monkeypatch):
    """A cache of this test's own: the model's library is not in it until the test builds it."""
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))


def sweep(out, *extra) -> int:
    return cli.main(["sweep", str(SPRING_MASS), *STUDY, "--out", str(out), *extra])


def rows(out) -> pd.DataFrame:
    return pd.read_csv(out / "sweep.csv").drop(columns="wall_s")


def metadata(out) -> dict:
    return json.loads((out / "metadata.json").read_text())


def cut(out, kept: int) -> None:
    """sweep.csv as a kill after `kept` runs leaves it (header and those rows)."""
    lines = (out / "sweep.csv").read_text().splitlines(keepends=True)
    (out / "sweep.csv").write_text("".join(lines[:1 + kept]))


@pytest.fixture
def studies(tmp_path, uncached, capsys):
    """A study started under auto on an uncached model (interpreted), cut to 2 of its 4 runs;
    then the library cached by a compiled study; and a fresh interpreted study."""
    part, compiled, whole = tmp_path / "part", tmp_path / "compiled", tmp_path / "whole"
    assert sweep(part) == 0
    assert ", interpreted" in capsys.readouterr().err
    assert metadata(part)["options"]["mode"] == metadata(part)["mode"] == "interpreted"
    cut(part, 2)
    assert sweep(compiled, "--mode", "compiled") == 0
    assert sweep(whole, "--mode", "interpreted") == 0
    capsys.readouterr()
    return part, compiled, whole


def test_a_resumed_study_keeps_its_earlier_mode(studies, capsys):
    part, compiled, whole = studies
    # the control: auto, asked afresh, would now run the rest compiled, and compiled rows differ
    assert study_mode(casmech.load(SPRING_MASS), 4, "auto") == "compiled"
    assert not rows(compiled).equals(rows(whole))
    assert sweep(part, "--resume") == 0
    err = capsys.readouterr().err
    assert "interpreted, 2 finished earlier" in err and "differ" not in err
    pd.testing.assert_frame_equal(rows(part), rows(whole), check_exact=True)  # bit for bit
    assert metadata(part)["mode"] == "interpreted"
    assert metadata(part)["study"]["runner"].startswith("interpreted")
    assert metadata(part)["options"]["resumed"] == {"earlier_runs": 2,
                                                    "earlier_mode": "interpreted"}


def test_a_mode_given_on_resume_wins_and_says_so(studies, capsys):
    part, compiled, whole = studies
    assert sweep(part, "--resume", "--mode", "compiled") == 0
    err = capsys.readouterr().err
    assert "the earlier runs ran interpreted, the rest run compiled" in err
    resumed = rows(part)
    pd.testing.assert_frame_equal(resumed[:2], rows(whole)[:2], check_exact=True)
    pd.testing.assert_frame_equal(resumed[2:], rows(compiled)[2:], check_exact=True)
    # the top-level mode is the runs' (the last part's), as the runner says; the earlier
    # part's is recorded beside it
    assert metadata(part)["mode"] == metadata(part)["options"]["mode"] == "compiled"
    assert metadata(part)["study"]["runner"].startswith("compiled")
    assert metadata(part)["options"]["resumed"] == {"earlier_runs": 2,
                                                    "earlier_mode": "interpreted"}


def test_the_api_resumes_in_the_earlier_mode(studies):
    part, compiled, whole = studies
    casmech.sweep(SPRING_MASS, samples=4, normal={"m": (2, 0.1)}, seed=2,
                  keep=["max(block.z)", "final(block.vz)"], workers=0, t_end=0.05, out=part,
                  resume=True)
    pd.testing.assert_frame_equal(rows(part), rows(whole), check_exact=True)
    cut(part, 2)
    with pytest.warns(UserWarning, match="the earlier runs ran interpreted, the rest run "
                                         "compiled"):
        casmech.sweep(SPRING_MASS, samples=4, normal={"m": (2, 0.1)}, seed=2,
                      keep=["max(block.z)", "final(block.vz)"], workers=0, t_end=0.05,
                      out=part, resume=True, mode="compiled")


@pytest.mark.parametrize("text, said", [
    (json.dumps({"options": {"mode": "turbo\u001b[2J"}}),
     "options.mode is 'turbo\\x1b[2J', not one of interpreted, compiled, batched"),
    (json.dumps({"options": {"mode": ["interpreted"]}}), "options.mode is ['interpreted']"),
    (json.dumps({"options": "interpreted"}), "options.mode is None"),
    ("{not json", "cannot be read"),
    (None, "does not exist"),
])
def test_a_damaged_earlier_mode_is_a_usage_error_unless_mode_is_given(tmp_path, capsys, text,
                                                                       said):
    out = tmp_path / "study"
    assert sweep(out, "--mode", "interpreted") == 0
    cut(out, 2)
    if text is None:
        (out / "metadata.json").unlink()
    else:
        (out / "metadata.json").write_text(text)
    capsys.readouterr()
    assert sweep(out, "--resume") == 2
    err = capsys.readouterr().err
    assert said in err and "pass --mode" in err and "\x1b" not in err
    assert len(pd.read_csv(out / "sweep.csv")) == 2  # nothing ran
    assert sweep(out, "--resume", "--mode", "interpreted") == 0  # the way out
    assert len(pd.read_csv(out / "sweep.csv")) == 4
