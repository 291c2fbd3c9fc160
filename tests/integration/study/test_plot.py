"""casmech.study.plot: `casmech plot DIR/sweep.csv` draws the kept outputs (lines against the
first grid parameter, a histogram for a sampled study), only complete runs."""

import json

import numpy as np
import pytest

from casmech import cli
from casmech.errors import UsageError
from casmech.study import plot


def write(tmp_path, rows, grid):
    header = "run,L,k,status,wall_s,max(bob.z),reason\n"
    (tmp_path / "sweep.csv").write_text(header + "".join(rows))
    (tmp_path / "metadata.json").write_text(json.dumps({"study": {"grid": grid}}))
    return tmp_path / "sweep.csv"


ROWS = ["0,1,10,complete,0.1,0.5,\n", "1,2,10,complete,0.1,0.7,\n",
        "2,1,20,complete,0.1,0.6,\n", "3,2,20,failed,0.1,nan,analysis failed at t = 0.1\n"]


def test_lines_against_the_first_grid_parameter(tmp_path):
    fig = plot.figure(write(tmp_path, ROWS, {"L": [1, 2], "k": [10, 20]}), [])
    (ax,) = fig.axes
    lines = {line.get_label(): (list(line.get_xdata()), list(line.get_ydata()))
             for line in ax.get_lines()}
    assert lines == {"k = 10": ([1, 2], [0.5, 0.7]), "k = 20": ([1], [0.6])}
    assert "1 failed" in fig._suptitle.get_text()


def test_histogram_of_a_sampled_study(tmp_path):
    fig = plot.figure(write(tmp_path, ROWS, {}), ["max(bob.z)"])
    (ax,) = fig.axes
    assert sum(patch.get_height() for patch in ax.patches) == 3  # the complete runs
    np.testing.assert_allclose(min(p.get_x() for p in ax.patches), 0.5, rtol=0, atol=1e-12)


def test_unknown_output(tmp_path):
    with pytest.raises(UsageError, match="did you mean 'max\\(bob.z\\)'"):
        plot.figure(write(tmp_path, ROWS, {"L": [1, 2]}), ["max(bob.y)"])


def test_command(tmp_path):
    path = write(tmp_path, ROWS, {"L": [1, 2]})
    assert cli.main(["plot", str(path), "-o", str(tmp_path / "p.png")]) == 0
    assert (tmp_path / "p.png").stat().st_size > 0
