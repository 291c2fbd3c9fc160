"""Results as DataFrames (output.frames): load_results of a real run's results.csv and results.h5
against the Result the API computes for the same model, overrides and settings; Result's repr
and notebook HTML show the summary."""

import numpy as np
import pandas as pd
import pytest

import casmech
from casmech.errors import UsageError
from casmech.io.csv import write_csv
from casmech.io.frames import load_results
from casmech.runtime.frames import frame
from casmech.runtime.results import Result, column_names
from tests.conftest import MODELS


@pytest.fixture(scope="module")
def api_result(slider_run):
    """What `casmech run slider_crank --set omega=3 --t-end 0.1` computes, through the API."""
    functions = casmech.compile(casmech.load(slider_run.model, {"omega": "3"}))
    return functions, casmech.analyze(functions, t_end=0.1)


@pytest.mark.parametrize("name", ["results.csv", "results.h5"])
def test_files_read_as_the_results_arrays(slider_run, api_result, name):
    functions, result = api_result
    data = load_results(slider_run.out / name)
    names = column_names(functions)
    assert data.index.name == "t" and list(data.columns) == names[1:]
    assert data.dtypes.eq(np.float64).all()
    # the run and the API evaluate the same SX functions (or the compiled library, which
    # differs by evaluation order): equal to 1e-12 of each column's scale
    expected = result.to_dataframe()
    scale = np.maximum(1.0, np.abs(expected.to_numpy()).max(axis=0))
    np.testing.assert_allclose(data.to_numpy() / scale, expected.to_numpy() / scale,
                               rtol=0, atol=1e-12)
    # times are the output grid both ways; the Result's own arrays are the frame's columns
    np.testing.assert_allclose(data.index, result.times, rtol=0, atol=1e-15)  # t = k * 0.01
    nb = functions.n_bodies
    crank = functions.body_names.index("crank")
    np.testing.assert_allclose(expected["crank.x"], result.q[:, 3 * crank], rtol=0, atol=0)
    np.testing.assert_allclose(expected["crank.e0"], result.q[:, 3 * nb + 4 * crank],
                               rtol=0, atol=0)  # copied, not computed
    np.testing.assert_allclose(expected["crank.vz"], result.q_dot[:, 3 * crank + 2],
                               rtol=0, atol=0)


def test_csv_and_hdf5_frames_are_identical(slider_run):
    """Shortest round-trip text and HDF5 binary64 both hold the doubles exactly."""
    from_csv, from_h5 = (load_results(slider_run.out, format=f) for f in ("csv", "hdf5"))
    np.testing.assert_allclose(from_h5.to_numpy(), from_csv.to_numpy(), rtol=0, atol=0)
    assert list(from_h5.columns) == list(from_csv.columns)
    assert from_h5.attrs["metadata"] == from_csv.attrs["metadata"]  # the same record
    assert from_csv.attrs["metadata"]["overrides"] == {"omega": "3"}
    assert from_csv.attrs["metadata"]["model"]["name"] == "slider_crank"


def test_units(slider_run):
    units = load_results(slider_run.out).attrs["units"]
    assert units["t"] == "s" and units["crank.x"] == "m" and units["crank.e2"] == "-"
    assert units["crank.wz"] == "rad/s" and units["crank.vx"] == "m/s"
    assert units["energy"] == "J" and units["constraint_violation"] == "-"
    joint = next(name for name in units if name.endswith(".fx"))
    assert units[joint] == "N" and units[joint[:-2] + "tz"] == "N m"


def test_round_trip_through_csv(tmp_path):
    """frame -> results.csv -> load_results gives the same numbers, awkward doubles included."""
    rng = np.random.default_rng(7)
    values = rng.standard_normal((5, 3)) * np.array([1e-300, 1.0, 1e300])
    values[:, 0] = np.arange(5) * 0.01  # 0.03 is not a binary fraction
    names = ["t", "b.x", "energy"]
    write_csv(tmp_path / "results.csv", names, values)
    back = load_results(tmp_path)
    np.testing.assert_allclose(back.reset_index().to_numpy(), values, rtol=0, atol=0)  # exact
    assert back.attrs["metadata"] == {}  # no metadata.json beside it
    assert frame(names, values).equals(back)


def test_folder_and_format_errors(tmp_path, slider_run):
    with pytest.raises(UsageError, match="no such results folder"):
        load_results(tmp_path / "missing")
    with pytest.raises(UsageError, match="holds no results.csv or results.h5"):
        load_results(tmp_path)
    with pytest.raises(UsageError, match="format 'xml'"):
        load_results(slider_run.out, format="xml")
    assert isinstance(casmech.load_results(slider_run.out / "results.h5"), pd.DataFrame)


def test_repr_and_html_summary(api_result):
    functions, result = api_result
    text, page = repr(result), result._repr_html_()
    columns = len(column_names(functions))
    for shown in ("slider_crank", "inverse_dynamics", "11", "0 .. 0.1 s", "complete",
                  str(columns)):
        assert shown in text and f"<td style=\"text-align:left\">{shown}" in page
    for label in ("model", "analysis", "rows", "time span", "status", "columns"):
        assert f">{label}</th>" in page
    assert len(page) < 2000  # a summary, not every stored list


def test_partial_rows_of_a_failure_tabulate(tmp_path):
    """The rows kept by a failure (four-bar with a crank too long to turn) know their
    functions and their status."""
    functions = casmech.compile(casmech.load(MODELS / "four_bar.yaml", {"a": "1.6"}))
    with pytest.raises(casmech.AnalysisError) as failure:
        casmech.analyze(functions, "kinematics")
    partial = failure.value.partial
    assert partial.status == "failed" and "status: failed" in repr(partial)
    assert len(partial.to_dataframe()) == len(partial) > 0


def test_result_without_functions():
    bare = Result("dynamics")
    assert "rows: 0" in repr(bare) and "time span: none" in repr(bare)
    with pytest.raises(ValueError, match="no system functions"):
        bare.to_dataframe()


def test_header_only_csv(tmp_path):
    """An interrupt before the first row leaves the header alone: an empty frame."""
    names = ["t", "b.x"]
    write_csv(tmp_path / "results.csv", names, np.zeros((0, 2)))
    empty = load_results(tmp_path)
    assert len(empty) == 0 and list(empty.columns) == ["b.x"] and empty.index.name == "t"
