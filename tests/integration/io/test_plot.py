"""casmech plot on real results: the drawn lines are the CSV's columns, units follow the column
suffixes, the files are a PNG and a PDF by their own readers, user mistakes are usage errors."""

import csv
import sys

import matplotlib.image
import numpy as np
import pytest

from casmech import cli
from casmech.errors import UsageError
from casmech.io import plot
from casmech.io.csv import read_csv
from casmech.io.hdf5 import read_hdf5
from tests.conftest import MODELS

# the brief's unit table, written out independently of casmech.io.plot.QUANTITIES
UNITS = {"x": "m", "y": "m", "z": "m", "vx": "m/s", "vy": "m/s", "vz": "m/s", "ax": "m/s²",
         "ay": "m/s²", "az": "m/s²", "e0": "-", "e1": "-", "e2": "-", "e3": "-",
         "wx": "rad/s", "wy": "rad/s", "wz": "rad/s", "alphax": "rad/s²", "alphay": "rad/s²",
         "alphaz": "rad/s²", "fx": "N", "fy": "N", "fz": "N", "tx": "N m", "ty": "N m",
         "tz": "N m", "energy": "J", "constraint_violation": "-"}


def stdlib_columns(path):
    """The CSV read with the standard library's csv module (not casmech's reader)."""
    with open(path, newline="") as handle:
        rows = list(csv.reader(handle))
    return {name: np.array([float(r[k]) for r in rows[1:]]) for k, name in enumerate(rows[0])}


def drawn(fig):
    """label -> (x, y) of every line of every panel."""
    return {line.get_label(): (line.get_xdata(), line.get_ydata())
            for ax in fig.axes for line in ax.get_lines()}


def test_lines_are_the_csv_columns(slider_run):
    table = stdlib_columns(slider_run.out / "results.csv")
    names, values = read_csv(slider_run.out / "results.csv")
    fig = plot.figure(names, values, ["positions", "energy", "reactions:crank_pivot"])
    lines = drawn(fig)
    expected = ([f"{b}.{c}" for b in ("crank", "rod", "slider") for c in "xyz"] + ["energy"]
                + [f"crank_pivot.{c}" for c in ("fx", "fy", "fz", "tx", "ty", "tz")])
    assert sorted(lines) == sorted(expected)
    for label, (x, y) in lines.items():
        # the file's numbers read back to the same binary64: the drawn data is the file's exactly
        np.testing.assert_allclose(x, table["t"], rtol=0, atol=0)
        np.testing.assert_allclose(y, table[label], rtol=0, atol=0)
    # positions (m), energy (J), force (N), torque (N m): four panels, one per quantity
    assert [ax.get_ylabel() for ax in fig.axes] == ["position [m]", "energy [J]", "force [N]",
                                                    "torque [N m]"]
    assert all(ax.get_title() and ax.get_legend() for ax in fig.axes)
    assert fig.axes[-1].get_xlabel() == "time t [s]"


def test_glob_units_and_log_scale(slider_run):
    names, values = read_csv(slider_run.out / "results.csv")
    fig = plot.figure(names, values, ["crank.*", "constraints"])
    for ax in fig.axes:
        suffixes = {line.get_label().rsplit(".", 1)[-1] for line in ax.get_lines()}
        units = {UNITS[s] for s in suffixes}
        assert len(units) == 1 and ax.get_ylabel().endswith(f"[{units.pop()}]")
    assert len(drawn(fig)) == 19 + 1  # every body column of the crank, and the violation
    assert [ax.get_yscale() for ax in fig.axes][-1] == "log"


def test_cli_writes_png_and_pdf(slider_run, tmp_path):
    png, pdf = tmp_path / "reactions.png", tmp_path / "positions.pdf"
    results = slider_run.out / "results.csv"
    assert cli.main(["plot", str(results), "reactions:wrist_pin", "-o", str(png)]) == 0
    assert cli.main(["plot", str(results), "-o", str(pdf)]) == 0  # default preset: positions
    image = matplotlib.image.imread(png)
    # figure 9 in wide at 120 dpi, two panels: 1.2 + 2 * 2.8 in high
    assert image.shape[:2] == (round(6.8 * 120), 9 * 120)
    # drawn, not blank: the default first line colour (tab:blue, #1f77b4) is on the image
    blue = np.all(np.abs(image[:, :, :3] - [0x1F / 255, 0x77 / 255, 0xB4 / 255]) < 0.02, axis=2)
    assert blue.sum() > 500
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF-") and data.rstrip().endswith(b"%%EOF")


def test_the_same_plot_from_hdf5(slider_run):
    fig_csv = plot.figure(*read_csv(slider_run.out / "results.csv"), ["slider.x"])
    fig_h5 = plot.figure(*read_hdf5(slider_run.out / "results.h5"), ["slider.x"])
    (x1, y1), (x2, y2) = drawn(fig_csv)["slider.x"], drawn(fig_h5)["slider.x"]
    # both files hold the same binary64 numbers
    np.testing.assert_allclose(np.c_[x2, y2], np.c_[x1, y1], rtol=0, atol=0)


@pytest.mark.parametrize("spec, expected", [
    ("crank.xx", "did you mean crank.x"),
    ("energi", "did you mean energy"),
    ("reactions:crank_pivo", "did you mean crank_pivot"),
    ("reactions", "reactions:JOINT"),
    ("crunk.*", "no column matches 'crunk.*'; did you mean crank."),
])
def test_unknown_columns_are_usage_errors_with_close_matches(slider_run, spec, expected):
    names, values = read_csv(slider_run.out / "results.csv")
    with pytest.raises(UsageError) as error:
        plot.figure(names, values, [spec])
    assert expected in str(error.value)


def test_cli_usage_errors_exit_2(slider_run, tmp_path, capsys):
    results = str(slider_run.out / "results.csv")
    assert cli.main(["plot", results, "nope", "-o", str(tmp_path / "a.png")]) == 2
    assert cli.main(["plot", results, "-o", str(tmp_path / "a.jpg")]) == 2
    err = capsys.readouterr().err
    assert "unknown column or preset 'nope'" in err and "expected a file name ending in" in err
    assert "Traceback" not in err and not (tmp_path / "a.png").exists()


def test_a_results_file_that_is_not_a_table_is_a_usage_error(tmp_path, capsys):
    """A results.csv edited by hand (a row short of values, a word among the numbers): exit 2
    naming the file and the row, no traceback."""
    for text, where in (("t,a,b\n0,1,2\n0.1,1\n", ":3:1: 2 values where the header names 3"),
                        ("t,a\n0,1\n0.1,x\n", ":3:5: 'x' is not a number")):
        path = tmp_path / "results.csv"
        path.write_text(text)
        assert cli.main(["plot", str(path), "a", "-o", str(tmp_path / "a.png")]) == 2
        err = capsys.readouterr().err
        assert f"{path}{where}; expected a table of numbers" in err
        assert "Traceback" not in err and not (tmp_path / "a.png").exists()


def test_missing_matplotlib_says_how_to_install_it(slider_run, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib.figure", None)  # import now fails
    with pytest.raises(UsageError, match=r"pip install matplotlib"):
        plot.figure(*read_csv(slider_run.out / "results.csv"), ["energy"])


def test_log_axis_keeps_round_off_floor():
    """An exact zero and a 1e-33 left by a projection must not stretch the log axis over 20
    decades: everything above round-off (1e-12 .. 1e-9 here) stays visible."""
    names = ["t", "constraint_violation"]
    values = np.array([[0.0, 0.0], [0.1, 1e-33], [0.2, 1e-12], [0.3, 1e-9]])
    (ax,) = plot.figure(names, values, ["constraints"]).axes
    bottom, top = ax.get_ylim()
    assert ax.get_yscale() == "log" and 1e-17 <= bottom <= 1e-12 and top >= 1e-9


def test_reactions_in_another_frame_get_their_own_titled_panel():
    """A joint whose reactions are in its joint frame (metadata reaction_frames) is not drawn
    in the panel of a global one, and its panel says which frame."""
    names = ["t", "a.fx", "b.fx", "c.x"]
    grouped = plot.panels(names[1:], {"a": "joint", "b": "global"})
    titles = {key[2]: columns for key, columns in grouped.items()}
    assert titles["joint reaction force on body_j (joint frame of each joint)"] == ["a.fx"]
    assert titles["joint reaction force on body_j (global)"] == ["b.fx"]
    assert titles["CM position (global)"] == ["c.x"]  # body columns are not reactions


def test_plot_command_reads_the_frames_from_the_runs_metadata(tmp_path):
    """casmech plot takes each joint's frame from metadata.json beside results.csv (and from
    results.h5's own metadata)."""
    from casmech.cli.plot import reaction_frames

    out = tmp_path / "run"
    assert cli.main(["run", str(MODELS / "slider_crank.yaml"), "--out", str(out), "--t-end",
                     "0.05", "--mode", "interpreted", "--reactions-frame", "joint",
                     "--format", "csv,hdf5"]) == 0
    expected = dict.fromkeys(("crank_pivot", "crank_pin", "wrist_pin", "slide"), "joint")
    assert reaction_frames(out / "results.csv") == expected
    assert reaction_frames(out / "results.h5") == expected
    assert reaction_frames(tmp_path / "elsewhere" / "results.csv") == {}  # no metadata: global
