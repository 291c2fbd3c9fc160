"""The `outputs:` block (docs/format.md#outputs): named values written as results columns,
read by events, optimal control's columns and plots; each checked against the same quantity
computed from the other columns of the table (numpy), and every error located."""

import numpy as np
import pytest

import casmech
from casmech.errors import ModelError
from casmech.io import plot
from casmech.optimal.dae import build_dae, columns_function
from casmech.optimal.system import parametric_system
from tests.conftest import Table

PENDULUM = """\
casmech: 1
name: pendulum
parameters: {L: 2.0, m: 3.0}
bodies:
  - {name: bar, mass: m, inertia: [0.01, 1.0, 1.0], position: [L/2, 0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 1, 0],
     reactions: {frame: joint}}
outputs:
  - {name: tip_z, value: 2 * bar.z}
  - {name: twice_tip, value: 2 * tip_z}
  - {name: pull, value: pivot.fx}
  - {name: spin_energy, value: "0.5 * m * L**2 / 3 * pivot.angle_dot**2 + t * 0"}
%s
analysis: {type: dynamics, t_end: 1.0, output_step: 0.01}
"""


def run(text: str, **settings):
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions, **settings)
    return functions, result, Table(*casmech.results_table(functions, result))


def test_outputs_are_columns_after_the_joint_states_with_their_values():
    functions, _, table = run(PENDULUM % "")
    assert table.names[-6:] == ["pivot.angle", "pivot.angle_dot", "tip_z", "twice_tip", "pull",
                                "spin_energy"]
    np.testing.assert_allclose(table["tip_z"], 2 * table["bar.z"], rtol=0, atol=1e-15)
    np.testing.assert_allclose(table["twice_tip"], 4 * table["bar.z"], rtol=0, atol=1e-15)
    # the reaction as the table writes it: the joint frame (reactions: {frame: joint})
    np.testing.assert_allclose(table["pull"], table["pivot.fx"], rtol=0, atol=1e-12)
    kinetic = 0.5 * 3.0 * 4.0 / 3 * table["bar.wy"] ** 2  # about the pivot (1 m from the CM)
    np.testing.assert_allclose(table["spin_energy"], kinetic, rtol=1e-9, atol=1e-12)


def test_an_event_reads_an_output():
    """The run stops where the tip falls 1.5 m below the pivot (2 bar.z = -1.5)."""
    events = "events:\n  - {name: low, when: tip_z + 1.5, direction: falling, action: stop}"
    _, result, table = run(PENDULUM % events)
    assert result.status == "stopped by event" and result.events[0].name == "low"
    np.testing.assert_allclose(table["tip_z"][-1], -1.5, rtol=0,
                               atol=1e-6)  # located to the run's tolerance (rtol 1e-8)


def test_optimal_controls_columns_hold_the_joint_states_and_outputs():
    """casmech.optimal's results columns (over theta) are the runtime's, at the initial
    state."""
    model = casmech.loads(PENDULUM % "")
    dae = build_dae(parametric_system(model))
    names, function = columns_function(dae)
    functions = casmech.compile(model)
    _, _, table = run(PENDULUM % "", analysis="assembly")
    x0 = np.concatenate([dae.q_assembled, dae.q_dot_assembled])
    from casmech.optimal.dae import consistent_algebraic

    z0 = consistent_algebraic(dae, x0, np.zeros(0))
    values = np.array(function(0.0, x0, z0, np.zeros(0))).ravel()
    assert names[-3:] == ["twice_tip", "pull", "spin_energy"] and len(names) == len(table.names) - 1
    for name in ("pivot.angle", "tip_z", "twice_tip", "spin_energy"):
        np.testing.assert_allclose(values[names.index(name)], table[name][0], rtol=0,
                                   atol=1e-12)  # the same formulas, numbers and SX
    assert functions.n_bodies == 1


def test_an_outputs_unit_is_the_dimension_of_what_it_reads():
    """A plain number has no stated dimension (it is SI of any), so a product with one has
    none either; sums, states, reactions and outputs read have theirs."""
    model = casmech.loads(PENDULUM % "")
    assert {o.name: o.unit for o in model.outputs} == {
        "tip_z": None, "twice_tip": None, "pull": "N", "spin_energy": None}
    more = PENDULUM.replace("outputs:\n", "outputs:\n  - {name: lever, value: pivot.fx * bar.z}\n"
                            "  - {name: drop, value: bar.z - 1}\n"
                            "  - {name: rate, value: 30 deg/s}\n", 1) % ""
    assert [o.unit for o in casmech.loads(more).outputs[:3]] == ["N m", "m", "rad/s"]
    with pytest.raises(ModelError) as caught:
        casmech.loads(PENDULUM.replace("value: 2 * bar.z}", "value: bar.z + bar.vz}") % "")
    [found] = caught.value.diagnostics
    assert (found.code, found.path) == ("E205", "outputs[0].value")
    assert found.message == "'+' of different dimensions: length (m) and velocity (m/s)"


def test_plot_labels_the_new_columns():
    names = ["t", "bar.wx", "ball.wx", "ball.fx", "pivot.angle", "slide.displacement_dot",
             "tip_z"]
    joints = frozenset(plot._joints(names))
    assert plot.panel_key("tip_z", None, joints, {"tip_z": "m"}) == ("tip_z", "m",
                                                                     "output tip_z")
    assert plot.panel_key("ball.wx", None, joints)[1:] == (
        "rad/s", "relative angular velocities of spherical joints (joint frame)")
    assert plot.panel_key("bar.wx", None, joints)[2] == "angular velocity (global)"
    assert plot.panel_key("pivot.angle", None, joints)[1] == "rad"
    assert plot.panel_key("slide.displacement_dot", None, joints)[1] == "m/s"


@pytest.mark.parametrize(("outputs", "code", "path", "message"), [
    ("  - {name: a, value: bar.zz}", "E201", "outputs[0].value", "body 'bar' has no 'zz'"),
    ("  - {name: a, value: pivot.angel}", "E201", "outputs[0].value",
     "revolute joint 'pivot' has no 'angel'"),
    ("  - {name: a, value: b + 1}", "E201", "outputs[0].value", "unknown symbol 'b'"),
    ("  - {name: a, value: 1}\n  - {name: a, value: 2}", "E301", "outputs[1].name",
     "duplicate output name 'a'"),
    ("  - {name: L, value: 1}", "E301", "outputs[0].name", "output name 'L' is a parameter's"),
    ("  - {name: energy, value: 1}", "E302", "outputs[0].name", "'energy' is a reserved name"),
    ("  - {name: a.b, value: 1}", "E303", "outputs[0].name", "invalid name 'a.b'"),
])
def test_output_errors_are_located(outputs, code, path, message):
    text = PENDULUM.replace("outputs:\n", "outputs:\n" + outputs + "\n", 1) % ""
    with pytest.raises(ModelError) as caught:
        casmech.loads(text)
    found = caught.value.diagnostics[0]
    assert (found.code, found.path) == (code, path)
    assert found.message.startswith(message)


def test_an_event_cannot_read_an_output_that_reads_reactions():
    events = "events:\n  - {name: hard, when: pull - 10}"
    with pytest.raises(ModelError) as caught:
        casmech.loads(PENDULUM % events)
    [found] = caught.value.diagnostics
    assert (found.code, found.path) == ("E201", "events[0].when")
    assert "reads reactions (pivot.fx)" in found.message
    assert (found.source.line, found.source.col) == (15, 24)  # `pull` in `when`


def test_a_sweep_keeps_an_output():
    """A study's kept values read outputs as any column (study/kept.py on the run's table)."""
    from casmech.study import kept

    functions = casmech.compile(casmech.loads(PENDULUM % ""))
    result = casmech.analyze(functions)
    names, values = casmech.results_table(functions, result)
    wanted = [kept.parse("min(tip_z)"), kept.parse("twice_tip@0.5")]
    for item in wanted:
        kept.check(item, names, 1.0)
    found = kept.values(wanted, names, values)
    table = Table(names, values)
    assert found["min(tip_z)"] == pytest.approx(table["tip_z"].min(), abs=0)
    np.testing.assert_allclose(found["twice_tip@0.5"], 4 * table["bar.z"][50], rtol=0,
                               atol=1e-15)  # the row at t = 0.5 exactly
