"""casmech run when the results go wrong (issue 35 items 5 and 6): a results row that is not
finite stops the run there (exit 3) naming the time, the column and the element, the rows
before it kept; a results file the disk refuses (a file-size limit, a full disk, a read-only
folder) ends the run with exit 4 naming the path and the cause, the rows written before kept,
metadata.json saying failed; and the rows are on disk while the run goes."""

import json
import os
import re
import resource
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import casmech
from casmech import cli
from casmech.errors import AnalysisError
from casmech.io.csv import read_csv
from casmech.io.hdf5 import read_hdf5, read_hdf5_metadata
from tests.conftest import MODELS, ROOT
from tests.texts import pendulum

ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1",
       "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])}

# a slider driven along x through the point the spring is anchored at: at t = 0.5 the spring's
# points coincide and the direction of its force (free length 0) is 0/0
PASSING = """\
casmech: 1
name: passing
gravity: [0, 0, 0]
bodies:
  - {name: slider, mass: 2, inertia: [1, 1, 1], position: [0, 0, 0]}
joints:
  - name: rail
    type: translational
    body_i: ground
    body_j: slider
    at: [0, 0, 0]
    axis: [1, 0, 0]
    driver: {displacement: t}
forces:
  - {name: spring, type: tsda, body_i: ground, at_i: [0.5, 0, 0], body_j: slider,
     at_j: [0, 0, 0], stiffness: 10, free_length: 0}
analysis: {type: ANALYSIS, t_end: 1, output_step: 0.1}
"""


def write(tmp_path, text: str, analysis: str):
    path = tmp_path / "model.yaml"
    path.write_text(text.replace("ANALYSIS", analysis))
    return path


@pytest.mark.parametrize("analysis", ["kinematics", "dynamics"])
def test_a_driver_whose_rate_overflows_stops_at_the_first_row(tmp_path, capsys, analysis):
    """angle 1e300 t: the rate 1e300 rad/s is finite, its square in the accelerations is not
    (before: NaN in 13 columns, exit 0, or a LinAlgError traceback)."""
    path = write(tmp_path, pendulum("1e300*t", "ANALYSIS"), analysis)
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out")]) == 3
    err = capsys.readouterr().err
    # the first column not finite: an acceleration of bar (which one depends on how the
    # analysis solves them: a saddle solve at the row's state keeps ax, off the y-z plane, 0)
    assert re.search(r"analysis failed at t = 0: the results are not finite from this row on "
                     r"\(bar\.a[xyz] = nan\)", err), err
    assert f"{path}:12:5: joint 'pivot': rotation angle = f(t): its rate nu = 1e+300" in err
    meta = json.loads((tmp_path / "out/metadata.json").read_text())
    assert (meta["status"], meta["rows"]) == ("failed", 0) and "not finite" in meta["error"]
    assert not (tmp_path / "out/results.csv").exists()  # no row before it: the metadata only


@pytest.mark.parametrize("analysis, column", [("inverse_dynamics", "rail.fx..tz"),
                                              ("dynamics", "rail.fx..tz")])
@pytest.mark.parametrize("form", ["csv", "hdf5"])
def test_rows_before_the_first_row_not_finite_are_kept(tmp_path, capsys, analysis, column,
                                                       form):
    path = write(tmp_path, PASSING, analysis)
    out = tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out), "--format", form]) == 3
    err = capsys.readouterr().err
    assert f"analysis failed at t = 0.5: the results are not finite from this row on ({column}" \
           in err
    assert f"{path}:15:5: force 'spring': its generalized force or potential is not finite" \
           in err
    names, values = (read_csv(out / "results.csv") if form == "csv"
                     else read_hdf5(out / "results.h5"))
    meta = (json.loads((out / "metadata.json").read_text()) if form == "csv"
            else read_hdf5_metadata(out / "results.h5"))
    assert (meta["status"], meta["rows"]) == ("failed", 5)
    # the rows kept are those of a run that stops before t = 0.5, and every one is finite
    functions = casmech.compile(casmech.load(path))
    whole = casmech.analyze(functions, t_end=0.4)
    expected_names, expected = casmech.results_table(functions, whole)
    assert names == expected_names
    np.testing.assert_array_equal(values, expected)  # the same code on the same states


def test_the_api_raises_with_the_rows_before(tmp_path):
    functions = casmech.compile(casmech.load(write(tmp_path, PASSING, "dynamics")))
    with pytest.raises(AnalysisError) as caught:
        casmech.analyze(functions)
    assert caught.value.partial.times == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4], abs=1e-12)
    assert "force 'spring'" in str(caught.value)


def test_a_tsda_whose_points_coincide_at_the_start_fails_at_the_first_row(tmp_path, capsys):
    text = PASSING.replace("at_i: [0.5, 0, 0]", "at_i: [0, 0, 0]")
    path = write(tmp_path, text, "dynamics")
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out")]) == 3
    err = capsys.readouterr().err
    assert "analysis failed at t = 0: the results are not finite" in err
    assert "force 'spring'" in err and "Traceback" not in err


# ------------------------------------------------------------------------------ the disk
def casmech_process(args, cwd, limit_bytes=None, timeout=120):
    def limits():
        if limit_bytes is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, limit_bytes))

    done = subprocess.run([sys.executable, "-m", "casmech.cli", *map(str, args)], cwd=cwd,
                          env=ENV, capture_output=True, text=True, timeout=timeout,
                          preexec_fn=limits)
    return done.returncode, done.stdout + done.stderr


def reference(tmp_path, t_end: float):
    """The run's table, interpreted as the runs compared with it are: the double pendulum is
    chaotic, and C's roundoff against CasADi's virtual machine grows to 1e-4 in 20 s."""
    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"), "interpreted")
    return casmech.results_table(functions, casmech.analyze(functions, t_end=t_end))[1]


@pytest.mark.parametrize("form", ["csv", "hdf5"])
def test_a_file_size_limit_ends_the_run_with_the_rows_written(tmp_path, form):
    """RLIMIT_FSIZE (ulimit -f) of 512 kB on a 20 s run of the double pendulum (about 2 MB of
    CSV, 0.85 MB of HDF5): exit 4 naming the file and the cause; the rows written are whole
    and exactly the first rows of the run; metadata says failed with that many rows (HDF5:
    the file is still readable, before: a segmentation fault of the HDF5 library)."""
    name = {"csv": "results.csv", "hdf5": "results.h5"}[form]
    code, output = casmech_process(["run", MODELS / "double_pendulum.yaml", "--out", "out",
                                    "--t-end", "20", "--format", form, "--mode",
                                    "interpreted"], tmp_path,
                                   limit_bytes=1 << 19)
    assert code == 4, output
    assert f"casmech: cannot write out/{name}: File too large" in output
    assert "Traceback" not in output
    if form == "csv":
        names, values = read_csv(tmp_path / "out/results.csv")
        meta = json.loads((tmp_path / "out/metadata.json").read_text())
        assert (meta["status"], meta["rows"]) == ("failed", len(values))
        assert "File too large" in meta["error"]
    else:
        names, values = read_hdf5(tmp_path / "out/results.h5")
    assert 100 < len(values) < 2001  # some rows fit, not all
    np.testing.assert_array_equal(values, reference(tmp_path, 20.0)[:len(values)])


def unshare_available() -> bool:
    try:
        return subprocess.run(["unshare", "-rm", "true"], capture_output=True,
                              timeout=10).returncode == 0
    except (OSError, subprocess.SubprocessError):
        return False


def in_tmpfs(tmp_path, options: str, args) -> str:
    """The output of casmech ARGS with `mnt` a tmpfs mounted with `options`, in a user and
    mount namespace of its own (no privileges needed, nothing mounted outside it), then
    `exit=CODE` and metadata.json."""
    (tmp_path / "mnt").mkdir()
    command = (f"mount -t tmpfs -o {options} tmpfs mnt && {sys.executable} -m casmech.cli "
               f"{' '.join(map(str, args))}; echo exit=$?; cat mnt/out/metadata.json "
               "2>/dev/null")
    done = subprocess.run(["unshare", "-rm", "sh", "-c", command], cwd=tmp_path, env=ENV,
                          capture_output=True, text=True, timeout=120)
    return done.stdout + done.stderr


needs_unshare = pytest.mark.skipif(not unshare_available(),
                                   reason="user namespaces (unshare -rm) not available")


@needs_unshare
def test_a_full_disk_ends_the_run_with_the_rows_written(tmp_path):
    output = in_tmpfs(tmp_path, "size=512k", ["run", MODELS / "double_pendulum.yaml", "--out",
                                              "mnt/out", "--t-end", "20"])
    assert "exit=4" in output and "Traceback" not in output, output
    assert "casmech: cannot write mnt/out/results.csv: No space left on device" in output
    meta = json.loads(output[output.index("{"):output.rindex("}") + 1])
    assert meta["status"] == "failed" and 100 < meta["rows"] < 2001


@needs_unshare
def test_a_read_only_folder_ends_the_run_before_it_starts(tmp_path):
    output = in_tmpfs(tmp_path, "ro,size=512k", ["run", MODELS / "double_pendulum.yaml",
                                                 "--out", "mnt/out"])
    assert "exit=4" in output and "Traceback" not in output, output
    assert "casmech: cannot write mnt/out: Read-only file system; no rows written" in output


def test_an_output_folder_under_a_file_ends_the_run(tmp_path):
    (tmp_path / "notes").write_text("a file, not a folder")
    code, output = casmech_process(["run", MODELS / "double_pendulum.yaml", "--out",
                                    "notes/out"], tmp_path)
    assert code == 4 and "casmech: cannot write notes/out" in output, output
    assert "Not a directory; no rows written" in output and "Traceback" not in output


def test_rows_are_on_disk_while_the_run_goes(tmp_path):
    """A run killed outright (SIGKILL) leaves the rows written so far: whole rows, in time
    order (a row the kill cut short, the last line without its newline, is not read back), and
    metadata.json saying running."""
    text = (MODELS / "double_pendulum.yaml").read_text().replace(
        "t_end: 2", "t_end: 10000").replace("output_step: 0.01", "output_step: 0.1")
    (tmp_path / "long.yaml").write_text(text)
    process = subprocess.Popen([sys.executable, "-m", "casmech.cli", "run", "long.yaml", "--out",
                                "out"], cwd=tmp_path, env=ENV, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            time.sleep(0.5)
            results = tmp_path / "out/results.csv"
            if results.exists() and results.read_bytes().count(b"\n") > 50:
                break
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    names, values = read_csv(tmp_path / "out/results.csv")
    assert len(values) > 49 and values.shape[1] == len(names)
    assert (np.diff(values[:, 0]) > 0).all()
    assert json.loads((tmp_path / "out/metadata.json").read_text())["status"] == "running"


def test_a_model_error_found_by_the_analysis_leaves_no_results_file(tmp_path, capsys):
    """kinematics of a pendulum without a driver: E501 from the analysis, exit 1; the results
    file opened for the rows is removed, metadata.json says failed (not running)."""
    text = pendulum(analysis="ANALYSIS")
    path = write(tmp_path, text, "kinematics")
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out")]) == 1
    assert "error[E501]" in capsys.readouterr().err
    assert not (tmp_path / "out/results.csv").exists()
    assert json.loads((tmp_path / "out/metadata.json").read_text())["status"] == "failed"
