"""casmech run with events (cli/run.py): events.csv beside results.csv, the event rows in
metadata.json, status "stopped by event" with exit 0, one printed line per event."""

import json
import math

import numpy as np

from casmech import cli
from casmech.io.csv import read_csv

MODEL = """casmech: 1
name: falling
bodies:
  - {name: ball, mass: 1, inertia: [1, 1, 1], position: [0, 0, 0]}
events:
  - {name: half, when: "ball.z + 0.35", direction: falling}
  - {name: low, when: "ball.z + 0.7", direction: falling, action: stop}
analysis: {type: dynamics, t_end: 1, output_step: 0.1, rtol: 1e-10, atol: 1e-12}
"""


def test_run_writes_events_and_stops(tmp_path, capsys):
    path = tmp_path / "falling.yaml"
    path.write_text(MODEL)
    out = tmp_path / "run"
    assert cli.main(["run", str(path), "--out", str(out), "--mode", "interpreted"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[1:] == [f"event half (falling) at t = {math.sqrt(0.7 / 9.81):.10g} s",
                           f"event low (falling) at t = {math.sqrt(1.4 / 9.81):.10g} s: "
                           "run stopped"]
    _, results = read_csv(out / "results.csv")
    with open(out / "events.csv") as handle:
        header = handle.readline().strip().split(",")
        lines = [line.strip().split(",") for line in handle]
    assert header[:3] == ["t", "name", "ball.x"]
    assert [line[1] for line in lines] == ["half", "low"]
    # free fall: z = -g t^2 / 2 at the event; rtol 1e-10 integration
    exact = [math.sqrt(0.7 / 9.81), math.sqrt(1.4 / 9.81)]
    np.testing.assert_allclose([float(line[0]) for line in lines], exact, rtol=0, atol=1e-9)
    z = header.index("ball.z")
    np.testing.assert_allclose([float(line[z]) for line in lines], [-0.35, -0.7], rtol=0,
                               atol=1e-9)
    assert results[-1, 0] == float(lines[-1][0])  # the stop event's row is the last row
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["status"] == "stopped by event" and meta["rows"] == len(results)
    assert [e["name"] for e in meta["events"]] == ["half", "low"]
    assert meta["events"][1]["values"]["ball.z"] == float(lines[1][z])
    assert cli.main(["run", "--replay", str(out / "metadata.json")]) == 0


def test_run_with_hdf5_too(tmp_path):
    """results.h5 beside events.csv (its metadata holds no list of event records)."""
    path = tmp_path / "falling.yaml"
    path.write_text(MODEL)
    out = tmp_path / "run"
    assert cli.main(["run", str(path), "--out", str(out), "--mode", "interpreted",
                     "--format", "csv,hdf5"]) == 0
    assert (out / "results.h5").is_file() and (out / "events.csv").is_file()
    assert json.loads((out / "metadata.json").read_text())["status"] == "stopped by event"
