"""results.h5 and metadata.json of a real run: the table read back with h5py is the CSV of the
same run; the metadata is right when recomputed from its sources (file bytes, installed
versions, the YAML read by PyYAML, the command line, a wall clock)."""

import hashlib
import json
import re
import sys
from importlib.metadata import version

import casadi
import h5py
import numpy as np
import pytest
import yaml

import casmech
from casmech import cli
from casmech.backends import codegen
from casmech.errors import UsageError
from casmech.io.csv import read_csv
from casmech.io.hdf5 import read_hdf5, read_hdf5_metadata, write_hdf5
from tests.conftest import MODELS


def test_hdf5_table_equals_csv(slider_run):
    names, values = read_csv(slider_run.out / "results.csv")
    with h5py.File(slider_run.out / "results.h5", "r") as handle:  # h5py itself, no helper
        table = handle["results"][()]
        columns = list(handle["columns"].asstr()[()])
    assert columns == names and table.dtype == np.float64
    # the CSV's shortest round-trip text and HDF5 binary64 are both exact; the brief asks for 1e-15
    np.testing.assert_allclose(table, values, rtol=1e-15, atol=0)
    assert table.shape == (11, len(names))  # t = 0, 0.01, .., 0.1


def test_metadata_recomputed_from_sources(slider_run):
    meta = read_hdf5_metadata(slider_run.out / "results.h5")
    raw = slider_run.model.read_bytes()
    assert meta["model"]["sha256"] == hashlib.sha256(raw).hexdigest()
    assert meta["model"]["text"] == raw.decode("utf-8")
    assert meta["model"]["file"] == "slider_crank.yaml"
    assert meta["casmech_version"] == version("casmech")
    assert meta["casadi_version"] == casadi.__version__
    assert meta["overrides"] == {"omega": "3"}
    # every parameter's value as the run used it: the override, and the file's own values
    given = yaml.safe_load(raw)["parameters"]
    assert meta["parameters"]["omega"] == 3.0
    assert set(meta["parameters"]) == set(given)
    assert all(meta["parameters"][k] == v for k, v in given.items()
               if k != "omega" and isinstance(v, (int, float)))
    analysis = yaml.safe_load(raw)["analysis"]  # the model's own block, read by PyYAML
    assert meta["analysis"]["type"] == analysis["type"] == "inverse_dynamics"
    assert meta["analysis"]["t_end"] == 0.1  # from --t-end
    assert meta["analysis"]["output_step"] == analysis["output_step"]
    assert meta["analysis"]["formulation"] == "auto"  # the default; the model names none
    # casmech run's default --mode auto ran what codegen.auto_mode decides for this model
    # (compiled if cached, else interpreted for a model this small; nothing built since)
    assert meta["mode"] == codegen.auto_mode(casmech.load(slider_run.model, {"omega": "3"}))
    assert meta["status"] == "complete"
    assert meta["rows"] == 11
    timings = meta["timings_s"]
    assert set(timings) == {"load", "compile", "analysis"}
    assert all(value > 0 for value in timings.values())
    assert sum(timings.values()) < slider_run.wall  # measured inside the run that was timed
    # the side file for CSV users holds the very same record
    assert json.loads((slider_run.out / "metadata.json").read_text()) == meta


def test_dynamics_settings_and_failure_status(tmp_path):
    """A dynamics run records the integrator settings it used; a failed run (four-bar with a
    crank too long to turn, stopping near t = 0.35 s) keeps its rows in both formats and says
    it failed."""
    out = tmp_path / "a01"
    argv = ["run", str(MODELS / "validation" / "iftomm_a01_pendulum.yaml"), "--out", str(out),
            "--t-end", "0.02", "--rtol", "1e-6", "--formulation", "romega", "--format", "hdf5"]
    assert cli.main(argv) == 0
    meta = read_hdf5_metadata(out / "results.h5")
    assert meta["analysis"]["rtol"] == 1e-6 and meta["analysis"]["formulation"] == "romega"
    assert meta["result"]["formulation"] == "romega"  # what the integrator reports it ran
    assert not (out / "results.csv").exists() and not (out / "metadata.json").exists()

    out = tmp_path / "toggle"
    argv = ["run", str(MODELS / "four_bar.yaml"), "--set", "a=1.6", "--out", str(out),
            "--analysis", "kinematics", "--format", "csv,hdf5"]
    assert cli.main(argv) == 3
    names, values = read_csv(out / "results.csv")
    h5_names, h5_values = read_hdf5(out / "results.h5")
    assert h5_names == names and len(values) >= 30
    np.testing.assert_allclose(h5_values, values, rtol=1e-15, atol=0)  # exact, as above
    meta = read_hdf5_metadata(out / "results.h5")
    assert meta["status"] == "failed" and "analysis failed at t = " in meta["error"]
    assert meta["rows"] == len(values)


def test_writer_round_trips_nested_metadata(tmp_path):
    metadata = {"a": 1, "b": {"c": "x", "d": {"e": 2.5}}, "text": "long\ntext", "f": True,
                "g": [1.5, 2.5], "h": ["rp", "romega"]}
    values = np.arange(6.0).reshape(2, 3)
    path = write_hdf5(tmp_path / "r.h5", ["t", "p.x", "p.y"], values, metadata)
    assert read_hdf5_metadata(path) == metadata
    names, back = read_hdf5(path)
    assert names == ["t", "p.x", "p.y"]
    np.testing.assert_allclose(back, values, rtol=0, atol=0)  # small integers: exact


def test_writes_leave_no_temporary_file(tmp_path):
    """Each write goes through a temporary name of its own, renamed or removed: a finished
    write and a failed one (a table that does not match its names) leave only results.h5."""
    names, values = ["t", "p.x"], np.arange(4.0).reshape(2, 2)
    write_hdf5(tmp_path / "results.h5", names, values)
    with pytest.raises(ValueError):
        write_hdf5(tmp_path / "results.h5", ["t", "p.x", "p.y"], np.arange(4.0))
    assert [p.name for p in tmp_path.iterdir()] == ["results.h5"]
    np.testing.assert_array_equal(read_hdf5(tmp_path / "results.h5")[1], values)  # the first


def test_missing_h5py_is_a_usage_error_before_the_run(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "h5py", None)  # import now fails
    argv = ["run", str(MODELS / "slider_crank.yaml"), "--out", str(tmp_path), "--format", "hdf5"]
    assert cli.main(argv) == UsageError.exit_code
    assert "pip install h5py" in capsys.readouterr().err
    assert not tmp_path.joinpath("results.h5").exists()


def test_unknown_format_is_a_usage_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        cli.main(["run", str(MODELS / "slider_crank.yaml"), "--format", "csv,xml"])
    assert exit_.value.code == 2
    assert "unknown format 'xml'" in capsys.readouterr().err


def test_a_file_that_is_not_a_results_h5_is_a_usage_error(tmp_path, monkeypatch):
    """Random bytes, HDF5 without the datasets, a table whose shape is not its columns', one
    claiming more values than a run writes (read no further than its shape): each a UsageError
    naming the file."""
    from casmech.schema import limits

    (tmp_path / "noise.h5").write_bytes(bytes(range(256)) * 8)
    with h5py.File(tmp_path / "empty.h5", "w") as handle:
        handle["other"] = np.zeros(3)
    with h5py.File(tmp_path / "shape.h5", "w") as handle:
        handle["columns"] = np.array([b"t", b"a"])
        handle["results"] = np.zeros((3, 5))
    with h5py.File(tmp_path / "large.h5", "w") as handle:
        handle["columns"] = np.array([b"t", b"a"])
        handle.create_dataset("results", shape=(1000, 2), dtype=float)  # never written
    monkeypatch.setattr(limits, "MAX_VALUES", 100)
    for name, cause in (("noise", "signature"), ("empty", "columns"), ("shape", "(3, 5)"),
                        ("large", "2000 values")):
        with pytest.raises(UsageError, match=rf"{name}.h5: not a results.h5 .*{re.escape(cause)}"):
            read_hdf5(tmp_path / f"{name}.h5")
