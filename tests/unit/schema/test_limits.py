"""Plausibility limits (schema/limits.py): magnitudes (E411), analysis settings and the output
grid (E409), and the other nonsense a model must not get past `check` with."""

import pytest

import casmech
from casmech.cli import main
from casmech.errors import ModelError
from casmech.schema import limits, load_model_text

MODEL = """\
casmech: 1
name: pend
gravity: [0, 0, -9.81]
bodies:
  - name: bar
    mass: 1
    inertia: [1, 1, 1]
    position: [0, 0, -1]
    velocity: [0, 0, 0]
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [1, 0, 0]}
forces:
  - {name: push, type: force, body: bar, value: [0, 0, 0]}
analysis: {type: dynamics, t_end: 1, output_step: 0.01, rtol: 1e-8, atol: 1e-10}
"""


def findings(text: str) -> list[tuple[str, str]]:
    with pytest.raises(ModelError) as caught:
        load_model_text(text, "m.yaml")
    return [(d.code, d.path) for d in caught.value.diagnostics]


def test_the_model_is_fine():
    load_model_text(MODEL)


@pytest.mark.parametrize("old, new, path", [
    ("position: [0, 0, -1]", "position: [0, 0, -2e6]", "bodies[0].position[2]"),
    ("velocity: [0, 0, 0]", "velocity: [1e300, 0, 0]", "bodies[0].velocity[0]"),
    ("mass: 1", "mass: 1e300", "bodies[0].mass"),
    ("inertia: [1, 1, 1]", "inertia: [1e13, 1e13, 1e13]", "bodies[0].inertia[0]"),
    ("gravity: [0, 0, -9.81]", "gravity: [0, 0, -1e300]", "gravity[2]"),
    ("axis: [1, 0, 0]", "axis: [1e300, 1e300, 0]", "joints[0].axis[0]"),
    ("at: [0, 0, 0]", "at: [0, 0, 1e7]", "joints[0].at[2]"),
    ("value: [0, 0, 0]", "value: [0, 0, '1e20 * (1 + t)']", "forces[0].value[2]"),
])
def test_magnitudes_beyond_the_limits_are_located(old, new, path):
    found = findings(MODEL.replace(old, new))
    assert ("E411", path) in found and {code for code, _ in found} == {"E411"}


def test_parameters_are_not_bounded_where_they_are_used_they_are():
    text = MODEL.replace("name: pend", "name: pend\nparameters: {big: 1e30, L: big / 1e30}")
    load_model_text(text.replace("position: [0, 0, -1]", "position: [0, 0, -L]"))
    assert findings(text.replace("mass: 1", "mass: big")) == [("E411", "bodies[0].mass")]


@pytest.mark.parametrize("setting, value, words", [
    ("rtol", "10", "between"), ("rtol", "1e-300", "between"), ("atol", "1e-300", "between"),
    ("atol", "0", "must be positive"), ("t_end", "1e300", "at most"),
    # subnormal numbers: t_end / output_step overflowed to an OverflowError traceback
    ("output_step", "2e-320", "at least"), ("output_step", "5e-324", "at least"),
    ("t_end", "1e-320", "at least"), ("output_step", "1e-13", "at least"),
])
def test_analysis_settings_within_limits(setting, value, words):
    text = MODEL.replace(f"{setting}: ", f"{setting}: {value}, _was: ")
    text = text.replace(", _was: " + {"rtol": "1e-8", "atol": "1e-10", "t_end": "1",
                                       "output_step": "0.01"}[setting], "")
    with pytest.raises(ModelError) as caught:
        load_model_text(text, "m.yaml")
    [diagnostic] = caught.value.diagnostics
    assert (diagnostic.code, diagnostic.path) == ("E409", f"analysis.{setting}")
    assert words in diagnostic.message and diagnostic.source.line == 14


def test_an_output_grid_too_large_is_refused_by_the_run_that_has_it(tmp_path, capsys):
    """The grid's size is a run's: a file whose own grid (1e9 rows) is too large loads; a run
    with its settings, and `casmech check`, give the located E409; a shorter t_end runs."""
    file = tmp_path / "m.yaml"
    file.write_text(MODEL.replace("output_step: 0.01", "output_step: 1e-9"))
    functions = casmech.compile(casmech.load(file))
    with pytest.raises(ModelError) as caught:
        casmech.analyze(functions)
    [diagnostic] = caught.value.diagnostics
    assert (diagnostic.code, diagnostic.path) == ("E409", "analysis.output_step")
    assert diagnostic.source.line == 14 and "output grid would have" in diagnostic.message
    assert len(casmech.analyze(functions, t_end=1e-6).times) == 1001  # 0, 1e-9, ..., 1e-6
    assert main(["check", str(file)]) == 1
    assert f"{file}:14:" in capsys.readouterr().err
    assert main(["run", str(file), "--t-end", "1e-6", "--out", str(tmp_path / "out"),
                 "-q"]) == 0
    assert main(["run", str(file), "--out", str(tmp_path / "out2"), "-q"]) == 1
    assert "error[E409]" in capsys.readouterr().err


def test_output_grid_counts_rows_and_columns():
    """1e5 rows of a 1-body, 1-joint model are fine; the same grid on 2000 bodies is not."""
    columns = 3 + 19 + 6
    assert limits.analysis_problems({"t_end": 1e3, "output_step": 0.01}, columns) == {}
    assert "output_step" in limits.analysis_problems({"t_end": 1e3, "output_step": 0.01},
                                                      3 + 19 * 2000)
    assert "output_step" in limits.analysis_problems({"t_end": 1e4, "output_step": 1e-3},
                                                      columns)


def test_grid_rows_of_an_overflowing_ratio_are_infinite():
    assert limits.grid_rows(1.0, 2e-320) == float("inf")
    assert limits.grid_rows(1.0, 0.25) == 6  # 0, 0.25, ..., 1 and one row to spare


OCP = MODEL + """\
ocp:
  horizon: 1
  intervals: 20
  controls: [{joint: pivot, type: torque}]
"""


@pytest.mark.parametrize("old, new, path", [
    ("horizon: 1", "horizon: 2e-320", "ocp.horizon"),
    ("horizon: 1", "horizon: 1e300", "ocp.horizon"),
    ("intervals: 20", "intervals: 100000000", "ocp.intervals"),
    ("intervals: 20", "intervals: 0", "ocp.intervals"),
    ("intervals: 20", "intervals: 20\n  elements: 0", "ocp.elements"),
    ("intervals: 20", "intervals: 200\n  elements: 100", "ocp.intervals"),
    ("intervals: 20", "intervals: 20\n  free_time: [1e-300, 2]", "ocp.free_time"),
])
def test_degenerate_ocp_settings_are_located(old, new, path):
    load_model_text(OCP)
    assert findings(OCP.replace(old, new)) == [("E409", path)]


JOINT = ("  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], "
         "axis: [1, 0, 0]}\n")


@pytest.mark.parametrize("old, new, expected", [
    ("name: pend", "name: my pendulum", ("E303", "name")),
    ("axis: [1, 0, 0]}", "axis: [1, 0, 0], driver: {}}", ("E100", "joints[0].driver")),
    ("joints:\n" + JOINT, "joints: null\n", ("E102", "joints")),
    ("gravity: [0, 0, -9.81]", "gravity: ~", ("E102", "gravity")),
])
def test_nonsense_is_reported(old, new, expected):
    assert expected in findings(MODEL.replace(old, new))


def test_an_empty_value_is_the_default_a_null_is_not():
    """`joints:` left empty means the default (no joints); `velocity: ~` is allowed where the
    key itself is optional without a default value."""
    assert load_model_text(MODEL.replace("joints:\n" + JOINT, "joints:\n")).joints == ()
    load_model_text(MODEL.replace("velocity: [0, 0, 0]", "velocity: ~"))
