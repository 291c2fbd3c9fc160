"""casmech run with a model kept in the cache (backends.checked_model): a run of an unchanged
model reads the kept one, imports no validation (PyYAML, pydantic, the schema checks), and
writes what a run that validates the file writes; a bad model's errors come every time."""

import json
import os
import re
import shutil
import subprocess
import sys

import pytest

from tests.conftest import MODELS

# runs the command line and prints, last on stderr, the modules the process imported (by an
# atexit handler: `casmech run` ends the process as it returns, cli._leave)
PROBE = ("import atexit, json, sys\nfrom casmech.cli import main\n"
         "atexit.register(lambda: print(json.dumps(sorted(sys.modules)), file=sys.stderr))\n"
         "sys.exit(main())")
VALIDATION = ("pydantic", "yaml", "casmech.schema.spec", "casmech.schema.semantic",
              "casmech.schema.loader")


def _run(tmp_path, *args):
    """(exit code, stdout, stderr without the probe's line, the modules imported)."""
    env = {**os.environ, "CASMECH_CACHE_DIR": str(tmp_path / "cache")}
    done = subprocess.run([sys.executable, "-c", PROBE, "run", *map(str, args)], env=env,
                          capture_output=True, text=True, timeout=300, cwd=tmp_path)
    *lines, modules = done.stderr.splitlines()
    return done.returncode, done.stdout, "\n".join(lines), set(json.loads(modules))


def _metadata(folder):
    meta = json.loads((folder / "metadata.json").read_text())
    for key in ("created_utc", "timings_s"):
        meta.pop(key)
    return meta


@pytest.mark.parametrize("name", ["quadruped_legs.yaml", "table_driver.yaml"])
def test_a_second_run_reads_the_kept_model_and_writes_the_same(tmp_path, name):
    shutil.copytree(MODELS, tmp_path / "models")
    model = tmp_path / "models" / name
    outputs = []
    for run in ("first", "second"):
        code, out, err, modules = _run(tmp_path, model, "--t-end", "0.05", "--out", run)
        assert code == 0, err
        # what it printed, but the analysis' seconds
        printed = re.sub(r"rows, [0-9.e-]+ s", "rows, T s", out.replace(run, "OUT"))
        outputs.append((printed, err, modules))
    (*printed_first, first), (*printed_second, second) = outputs
    assert [m for m in VALIDATION if m in first] == list(VALIDATION)  # the miss validated
    assert [m for m in VALIDATION if m in second] == []
    assert printed_first == printed_second
    assert (tmp_path / "first" / "results.csv").read_bytes() == \
        (tmp_path / "second" / "results.csv").read_bytes()
    assert _metadata(tmp_path / "first") == _metadata(tmp_path / "second")


def test_an_interpreted_run_validates_the_file(tmp_path):
    """--mode interpreted uses no cache, so no kept model either."""
    model = MODELS / "pendulum.yaml"
    for run in ("first", "second"):
        code, _, err, modules = _run(tmp_path, model, "--t-end", "0.05", "--out", run,
                                     "--mode", "interpreted")
        assert code == 0, err
        assert "pydantic" in modules
    assert not (tmp_path / "cache" / "checked-models").exists()


def test_a_bad_model_reports_its_errors_every_run(tmp_path):
    model = tmp_path / "bad.yaml"
    model.write_text((MODELS / "pendulum.yaml").read_text().replace("mass: m", "mass: -m"))
    found = [_run(tmp_path, model, "--t-end", "0.05")[:3] for _ in range(2)]
    assert found[0] == found[1] and found[0][0] == 1
    assert "bad.yaml:" in found[0][2] and "error[" in found[0][2]
    entries = tmp_path / "cache" / "checked-models"
    assert not entries.exists() or not any(p.is_dir() for p in entries.iterdir())


def test_cache_info_counts_the_kept_models_and_clear_removes_them(tmp_path, monkeypatch,
                                                                   capsys):
    from casmech.backends import checked_model
    from casmech.cli import main

    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))
    checked_model.load(MODELS / "pendulum.yaml")
    assert main(["cache", "info"]) == 0
    assert "and 1 checked models kept for runs of unchanged files" in capsys.readouterr().out
    assert main(["cache", "clear"]) == 0
    assert main(["cache", "info"]) == 0
    assert "checked models" not in capsys.readouterr().out
