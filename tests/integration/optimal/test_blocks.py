"""The estimate: and ocp: model blocks (schema) and the two commands that read them."""


import numpy as np
import pytest

import casmech
from casmech.cli import main
from casmech.errors import ModelError
from casmech.io.csv import read_csv
from casmech.optimal.ocp import from_block
from casmech.optimal.sensitivity import simulate
from tests.conftest import MODELS

SWING = (MODELS / "ocp_pendulum_swing_up.yaml").read_text()
BASE = SWING[:SWING.index("\nocp:")]


def codes(text: str) -> list[tuple[str, int]]:
    with pytest.raises(ModelError) as error:
        casmech.loads(text)
    return [(d.code, d.source.line if d.source else 0) for d in error.value.diagnostics]


def line_of(text: str, fragment: str) -> int:
    return text[:text.index(fragment)].count("\n") + 1


def test_blocks_resolve_to_numbers():
    model = casmech.load(MODELS / "ocp_pendulum_swing_up.yaml")
    problem, transcription = from_block(model.ocp)
    assert transcription == "collocation" and problem.intervals == 20
    assert (problem.controls[0].joint, problem.controls[0].lower) == ("pivot", -4.0)
    assert dict(problem.terminal) == {"bar.e0": 0.0, "bar.wx": 0.0}
    assert casmech.load(MODELS / "estimate_pendulum.yaml").estimate.parameters == ("m", "c")
    assert casmech.load(MODELS / "me751_pendulum.yaml").ocp is None  # optional blocks


def test_block_errors_point_at_their_lines():
    text = BASE + """
estimate:
  parameters: [m, mass]
  data: x.csv
  bounds: {m: [2, 1]}
ocp:
  horizon: -1
  controls: [{joint: pivt, bounds: [-1, 1]}]
"""
    found = codes(text)
    assert ("E300", line_of(text, "parameters: [m, mass]")) in found  # unknown parameter
    assert ("E409", line_of(text, "bounds: {m: [2, 1]}")) in found  # low > high
    assert ("E409", line_of(text, "horizon: -1")) in found
    assert ("E300", line_of(text, "controls: [{joint: pivt")) in found  # unknown joint


def test_optimize_command_writes_a_replayable_optimum(tmp_path, capsys):
    model = tmp_path / "swing.yaml"
    model.write_text(BASE + """
ocp:
  horizon: 1.0
  intervals: 8
  controls: [{joint: pivot, bounds: [-8, 8]}]
  terminal: {bar.e0: 0.8, bar.wx: 0}
""")
    assert main(["optimize", str(model), "--out", str(tmp_path / "out")]) == 0
    names, table = read_csv(tmp_path / "out" / "results.csv")
    # terminal equalities hold to IPOPT's constraint tolerance
    np.testing.assert_allclose(table[-1, [names.index("bar.e0"), names.index("bar.wx")]],
                               [0.8, 0.0], rtol=0, atol=1e-7)
    _, controls = read_csv(tmp_path / "out" / "controls.csv")
    assert controls.shape == (8, 2) and np.all(np.abs(controls[:, 1]) <= 8 + 1e-8)
    printed = capsys.readouterr().out
    assert "replay (DOP853 from every node): max position error" in printed
    # the replay's miss (Radau 3 on h = 1/8 s of a smooth swing): measured 1e-6 rad
    assert float(printed.split("max position error ")[1].split()[0]) <= 1e-4


def test_sensitivity_command(tmp_path, capsys):
    model = str(MODELS / "estimate_pendulum.yaml")
    args = ["sensitivity", model, "--parameter", "m", "--output", "bar.y", "--output",
            "energy", "--at", "0.5", "--csv", str(tmp_path / "s.csv")]
    assert main(args) == 0
    names, table = read_csv(tmp_path / "s.csv")
    assert names == ["output_index", "t", "value", "d/dm"] and table.shape == (2, 4)
    # the printed derivatives against central differences of re-loaded models (h = 1e-3 m)
    ends = [simulate(casmech.load(model, {"m": repr(1.5 + h)}), ["bar.y", "energy"], [0.5],
                     rtol=1e-12, atol=1e-14)[0] for h in (1.5e-3, -1.5e-3)]
    # relative 1e-5 as in test_sensitivity (measured ~1e-7 here)
    np.testing.assert_allclose(table[:, 3], (ends[0] - ends[1]) / 3e-3, rtol=1e-5, atol=1e-9)
    assert main(["sensitivity", model, "--wrt", "L", "--output", "bar.y", "--at", "1",
                 "--csv", str(tmp_path / "L.csv")]) == 0
    _, table = read_csv(tmp_path / "L.csv")
    ends = [simulate(casmech.load(model, {"L": repr(1.0 + h)}), ["bar.y"], [1.0],
                     rtol=1e-12, atol=1e-14)[0, 0] for h in (1e-3, -1e-3)]
    # second-order differences at h = 1e-3: h^2 truncation (measured 1e-7 relative)
    np.testing.assert_allclose(table[0, 3], (ends[0] - ends[1]) / 2e-3, rtol=1e-5, atol=1e-9)
    assert main(["sensitivity", model, "--wrt", "N", "--output", "bar.y", "--at", "1"]) == 2
    assert "neither a parameter of the model" in capsys.readouterr().err
    assert main(["sensitivity", model, "--parameter", "m", "--output", "bar.y",
                 "--at", "0"]) == 2


def test_free_final_time_block():
    text = BASE + """
ocp:
  horizon: 2
  free_time: [0.5, 3]
  objective: {effort: 0.1, time: 1}
  controls: [{joint: pivot}]
"""
    problem, _ = from_block(casmech.loads(text).ocp)
    assert problem.free_time == (0.5, 3.0) and problem.time_weight == 1.0
    assert problem.controls[0].lower == -np.inf  # no bounds written: unbounded
    bad = text.replace("free_time: [0.5, 3]", "free_time: [0, 3]")
    assert ("E409", line_of(bad, "free_time: [0, 3]")) in codes(bad)


def test_optimize_usage_errors(tmp_path, capsys):
    assert main(["optimize", str(MODELS / "me751_pendulum.yaml")]) == 2
    assert "neither an 'ocp:' nor an 'estimate:' block" in capsys.readouterr().err
    model = tmp_path / "fit.yaml"
    model.write_text(BASE + "\nestimate: {parameters: [m], data: missing.csv}\n")
    assert main(["optimize", str(model), "--out", str(tmp_path / "out")]) == 2
    assert "cannot read measurements" in capsys.readouterr().err
