"""casmech run --replay (cli/replay.py) and the reproducibility metadata it reads: the
sha256 of every file a model read, the versions and platform, the options. A replay gives the
rows of the recorded run; a changed or missing file is refused with a message naming it."""

import hashlib
import json
import platform
import shutil

import casadi
import numpy as np
import pytest

import casmech
from casmech import cli
from casmech.io.csv import read_csv
from casmech.io.hdf5 import read_hdf5_metadata
from tests.conftest import MODELS

# a driven pendulum reading a table (its driver) and naming a mesh (its picture)
MODEL = """\
casmech: 1
name: replay_pendulum
parameters: {L: 1.0, m: 2.0}
bodies:
  - name: bar
    mass: m
    inertia: [m*L**2/12, m*L**2/12, 1.0e-4]
    position: [0, 0, -L/2]
    geometry: [{mesh: bar.stl}]
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 1, 0],
     driver: {angle: {table: profile.csv, column: theta}}}
analysis: {type: inverse_dynamics, t_end: 0.4, output_step: 0.05}
"""
PROFILE = "t,theta\n" + "".join(f"{0.1 * k:.1f},{0.3 * np.sin(k):.6f}\n" for k in range(8))


@pytest.fixture()
def folder(tmp_path):
    (tmp_path / "pendulum.yaml").write_text(MODEL)
    (tmp_path / "profile.csv").write_text(PROFILE)
    (tmp_path / "bar.stl").write_text("solid bar\nendsolid bar\n")
    return tmp_path


def sha(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_metadata_records_files_versions_and_options(folder):
    out = folder / "run"
    argv = ["run", str(folder / "pendulum.yaml"), "--out", str(out), "--set", "m=3",
            "--format", "csv,hdf5", "--mode", "interpreted"]
    assert cli.main(argv) == 0
    meta = json.loads((out / "metadata.json").read_text())
    # every file the model read or named, hashed here independently of casmech
    assert meta["files"] == {name: {"path": str((folder / name).resolve()),
                                    "sha256": sha(folder / name)}
                             for name in ("pendulum.yaml", "profile.csv", "bar.stl")}
    assert meta["numpy_version"] == np.__version__
    assert meta["casadi_version"] == casadi.__version__
    assert meta["python_version"] == platform.python_version()
    assert meta["platform"] == platform.platform()
    assert meta["options"] == {"mode": "interpreted", "format": ["csv", "hdf5"],
                               "allow_dir": []}
    assert read_hdf5_metadata(out / "results.h5") == meta  # '/' in keys survives HDF5


def test_component_files_are_recorded():
    model = casmech.load(MODELS / "quadruped_legs.yaml")
    leg = (MODELS / "components" / "leg.yaml").resolve()
    assert model.sources[str(leg)] == sha(leg)
    assert model.sources[str((MODELS / "quadruped_legs.yaml").resolve())] == sha(
        MODELS / "quadruped_legs.yaml")


def test_replay_reproduces_the_rows(folder):
    out = folder / "run"
    assert cli.main(["run", str(folder / "pendulum.yaml"), "--out", str(out), "--set", "m=3",
                     "--t-end", "0.3", "--format", "csv,hdf5"]) == 0
    assert cli.main(["run", "--replay", str(out / "metadata.json")]) == 0
    again = folder / "run_replay"  # the default: DIR_replay beside DIR
    names, values = read_csv(out / "results.csv")
    replay_names, replay_values = read_csv(again / "results.csv")
    assert replay_names == names and len(values) == 7  # --t-end 0.3 was replayed
    # the same code on the same inputs: the same doubles
    np.testing.assert_allclose(replay_values, values, rtol=0, atol=0)
    first, second = (json.loads((d / "metadata.json").read_text()) for d in (out, again))
    for key in ("overrides", "analysis", "files", "parameters", "mode"):
        assert second[key] == first[key], key
    assert (again / "results.h5").is_file()  # the recorded formats


def test_replay_of_dynamics_settings(tmp_path):
    """Integrator settings given on the command line are replayed (r-p DAE, loose rtol)."""
    shutil.copy(MODELS / "double_pendulum.yaml", tmp_path)
    out, again = tmp_path / "a", tmp_path / "b"
    assert cli.main(["run", str(tmp_path / "double_pendulum.yaml"), "--out", str(out),
                     "--t-end", "0.2", "--rtol", "1e-5", "--formulation", "rp",
                     "--stabilization", "projection"]) == 0
    assert cli.main(["run", "--replay", str(out / "metadata.json"), "--out", str(again)]) == 0
    meta = json.loads((again / "metadata.json").read_text())
    assert meta["analysis"]["rtol"] == 1e-5 and meta["result"]["formulation"] == "rp"
    # deterministic integration of the same DAE: the same doubles
    np.testing.assert_allclose(read_csv(again / "results.csv")[1],
                               read_csv(out / "results.csv")[1], rtol=0, atol=0)


@pytest.mark.parametrize("change", ["pendulum.yaml", "profile.csv", "bar.stl"])
def test_changed_file_is_refused(folder, change, capsys):
    out = folder / "run"
    assert cli.main(["run", str(folder / "pendulum.yaml"), "--out", str(out)]) == 0
    with open(folder / change, "a") as handle:
        handle.write("\n# edited\n")
    again = folder / "again"
    code = cli.main(["run", "--replay", str(out / "metadata.json"), "--out", str(again)])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert f"{(folder / change).resolve()}: changed since the run" in err
    assert not again.exists()  # refused before anything was written


def test_missing_file_is_refused(folder, capsys):
    out = folder / "run"
    assert cli.main(["run", str(folder / "pendulum.yaml"), "--out", str(out)]) == 0
    (folder / "bar.stl").unlink()
    assert cli.main(["run", "--replay", str(out / "metadata.json")]) == 2
    assert "bar.stl: no longer exists" in capsys.readouterr().err


@pytest.mark.parametrize("extra, named", [(["--set", "m=1"], "--set"),
                                          (["--t-end", "1"], "--t-end"),
                                          (["MODEL.yaml"], "the model file")])
def test_replay_takes_no_run_options(folder, extra, named, capsys):
    out = folder / "run"
    assert cli.main(["run", str(folder / "pendulum.yaml"), "--out", str(out)]) == 0
    assert cli.main(["run", "--replay", str(out / "metadata.json"), *extra]) == 2
    assert named in capsys.readouterr().err


@pytest.mark.parametrize("text, message", [
    ("{", ":1:2: error[E001] not JSON: Expecting property name enclosed in double quotes"),
    ('{"model": {}}', ":1:11: error[E100] model.absolute_path: missing required key"),
    ("[1]", ":1:1: error[E003] the document is not a JSON object"),
    ("\xff\xfe", ":1:1: error[E001] not UTF-8 text"),
])
def test_unreadable_record(tmp_path, text, message, capsys):
    (tmp_path / "metadata.json").write_bytes(text.encode("latin-1"))
    assert cli.main(["run", "--replay", str(tmp_path / "metadata.json")]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path / 'metadata.json'}{message}" in err and "Traceback" not in err


def test_model_required_without_replay(capsys):
    assert cli.main(["run"]) == 2
    assert "needs a MODEL file" in capsys.readouterr().err


def test_allowed_folders_are_replayed(tmp_path, monkeypatch):
    """A table outside the model's folder, read under --allow-dir: the replay allows the same
    folder (and checks the table's hash) only when its command line names it again."""
    from casmech.schema import files

    monkeypatch.setattr(files, "_extra", [])  # the process-wide allowed folders, restored after
    model, data = tmp_path / "model", tmp_path / "data"
    model.mkdir(), data.mkdir()
    (model / "pendulum.yaml").write_text(MODEL.replace("profile.csv", "../data/profile.csv"))
    (data / "profile.csv").write_text(PROFILE)
    (model / "bar.stl").write_text("solid bar\nendsolid bar\n")
    out = model / "run"
    assert cli.main(["run", str(model / "pendulum.yaml"), "--out", str(out),
                     "--allow-dir", str(data)]) == 0
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["options"]["allow_dir"] == [str(data.resolve())]
    assert meta["files"][str((data / "profile.csv").resolve())]["sha256"] == sha(
        data / "profile.csv")  # outside the model's folder: keyed by its absolute path
    files._extra.clear()  # a fresh process: the record alone does not allow the folder ...
    assert cli.main(["run", "--replay", str(out / "metadata.json")]) == 2
    # ... the command line must repeat it
    assert cli.main(["run", "--replay", str(out / "metadata.json"), "--allow-dir",
                     str(data)]) == 0
    np.testing.assert_allclose(read_csv(model / "run_replay" / "results.csv")[1],
                               read_csv(out / "results.csv")[1], rtol=0, atol=0)  # same doubles
