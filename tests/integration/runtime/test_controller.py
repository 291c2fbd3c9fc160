"""A Python controller of a dynamics run (casmech.analyze(controller=...),
runtime/controller.py): the same law as a callback and as an expression in the model give the
same motion, in the joint formulation and in r-p; the state it reads is the results'; a
faulty controller is a located error with the rows before it kept."""

import math

import numpy as np
import pytest

import casmech
from casmech.errors import AnalysisError, UsageError
from tests.conftest import MODELS

PENDULUM = """
casmech: 1
name: pd_pendulum
parameters: {kp: 20.0, kd: 2.0}
gravity: [0, 0, -9.81]
bodies:
  - {name: bar, mass: 1.0, inertia: [0.1, 0.1, 0.01], position: [0.5, 0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 1, 0],
     motor: {torque: "LAW"}}
analysis: {type: dynamics, t_end: 1.5, output_step: 0.01, rtol: 1e-10, atol: 1e-12}
"""
PD = "-kp * angle - kd * angle_dot"
SLIDER = """
casmech: 1
name: forced_slider
gravity: [0, 0, -9.81]
bodies:
  - {name: block, mass: 2.0, inertia: [0.01, 0.01, 0.01], position: [1, 0, 0]}
joints:
  - {name: slide, type: translational, body_i: ground, body_j: block, at: [1, 0, 0],
     axis: [1, 0, 0], motor: {force: "LAW"}}
forces:
  - {name: spring, type: tsda, body_i: ground, at_i: [0, 0, 0], body_j: block,
     at_j: [1, 0, 0], stiffness: 50, free_length: 1}
analysis: {type: dynamics, t_end: 2, output_step: 0.01, rtol: 1e-10, atol: 1e-12}
"""


def compiled(text: str, law: str):
    return casmech.compile(casmech.loads(text.replace("LAW", law)))


def pd(t, state):
    return {"pivot": -20.0 * state["pivot.angle"] - 2.0 * state["pivot.angle_dot"]}


@pytest.mark.parametrize("formulation", ["joint", "rp", "romega"])
def test_pd_callback_matches_the_expression(formulation):
    """The PD law as a callback and as the motor's expression: the same motion and the same
    reaction torque (the motor's torque enters pivot.ty), to the integrator's tolerance."""
    written = casmech.analyze(compiled(PENDULUM, PD), formulation=formulation).to_dataframe()
    result = casmech.analyze(compiled(PENDULUM, "0"), formulation=formulation, controller=pd)
    called = result.to_dataframe()
    assert result.metadata["formulation"] == formulation
    assert result.metadata["controller"] == ["pivot.torque"]
    # the PD holds the bar off its rest: the law acts (its equilibrium, kp angle = m g L/2 cos)
    assert abs(written["pivot.angle"].iloc[-1]) > 0.1
    for column in ("pivot.angle", "pivot.angle_dot", "bar.x", "bar.z", "pivot.ty"):
        # two integrations of one ODE at rtol 1e-10: agree far below the motion's scale
        np.testing.assert_allclose(called[column], written[column], rtol=0, atol=1e-7)


def test_two_motors_by_an_array_in_the_order_given():
    """A double pendulum with a PD per joint, returned as an array in `controls` order (the
    elbow first), against the two expressions."""
    text = (MODELS / "double_pendulum.yaml").read_text()
    text = text.replace("    axis: [0, 1, 0]\n", "    axis: [0, 1, 0]\n    motor: {torque: LAW}\n")
    text = text.replace("t_end: 2", "t_end: 1").replace("rtol: 1.0e-8", "rtol: 1.0e-10")
    text = text.replace("atol: 1.0e-10", "atol: 1.0e-12")
    written = casmech.analyze(compiled(text, "'-30 * angle - 3 * angle_dot'")).to_dataframe()

    def law(t, state):
        return [-30 * state["elbow.angle"] - 3 * state["elbow.angle_dot"],
                -30 * state["pivot.angle"] - 3 * state["pivot.angle_dot"]]

    called = casmech.analyze(compiled(text, "0"), controller=law,
                             controls=["elbow", "pivot.torque"]).to_dataframe()
    for column in ("pivot.angle", "elbow.angle", "rod2.x", "rod2.z"):
        # rtol 1e-10 integrations of one chaotic-free short motion (1 s)
        np.testing.assert_allclose(called[column], written[column], rtol=0, atol=1e-6)


@pytest.mark.parametrize("formulation", ["joint", "rp"])
def test_a_loop_mechanism(formulation):
    """A four-bar with a PD on its crank (a DAE in both formulations)."""
    text = (MODELS / "four_bar_released.yaml").read_text().replace(
        "    initial: {angle: 30 deg, angle_dot: 60 deg/s}\n",
        "    initial: {angle: 30 deg, angle_dot: 60 deg/s}\n    motor: {torque: LAW}\n")
    settings = {"t_end": 0.5, "rtol": 1e-10, "atol": 1e-12, "formulation": formulation}
    written = casmech.analyze(compiled(text, "'-5 * angle - 0.5 * angle_dot'"),
                              **settings).to_dataframe()

    def law(t, state):
        return -5 * state["crank_pivot.angle"] - 0.5 * state["crank_pivot.angle_dot"]

    called = casmech.analyze(compiled(text, "0"), controller=law, **settings).to_dataframe()
    for column in ("crank_pivot.angle", "rocker.x", "rocker.y", "crank_pivot.tz"):
        # two rtol 1e-10 integrations of one DAE
        np.testing.assert_allclose(called[column], written[column], rtol=0, atol=1e-6)


@pytest.mark.parametrize("formulation", ["joint", "rp"])
def test_a_controller_of_time_matches_a_force_of_time(formulation):
    """A force motor on a slider: controller(t) = 3 sin(4 t) against `force: 3*sin(4*t)`, and
    both against the forced oscillator's closed form."""
    written = casmech.analyze(compiled(SLIDER, "3 * sin(4 * t)"),
                              formulation=formulation).to_dataframe()
    called = casmech.analyze(compiled(SLIDER, "0"), formulation=formulation,
                             controller=lambda t, state: {"slide.force": 3 * math.sin(4 * t)}
                             ).to_dataframe()
    # two rtol 1e-10 integrations of one ODE (IDAS: its Jacobian by finite differences)
    np.testing.assert_allclose(called["block.x"], written["block.x"], rtol=0, atol=1e-8)
    # m x'' + k x = F sin(w t), x(0) = x'(0) = 0: x = F/(k - m w^2) (sin w t - w/w0 sin w0 t)
    t, w, w0 = called.index.to_numpy(), 4.0, 5.0
    exact = 1 + 3 / (50 - 2 * 16) * (np.sin(w * t) - w / w0 * np.sin(w0 * t))
    # the closed form to the integrator's tolerance
    np.testing.assert_allclose(called["block.x"], exact, rtol=0, atol=1e-8)


@pytest.mark.parametrize("formulation", ["joint", "rp"])
def test_the_state_is_the_results_state(formulation):
    """What the controller reads at an output time is that row's results columns."""
    seen = {}

    def law(t, state):
        seen[round(t, 12)] = {k: state[k] for k in
                              ("bar.x", "bar.z", "bar.vx", "bar.wy", "pivot.angle",
                               "pivot.angle_dot")}
        return pd(t, state)

    table = casmech.analyze(compiled(PENDULUM, "0"), formulation=formulation,
                            controller=law).to_dataframe()
    rows = [t for t in table.index if round(t, 12) in seen]
    assert len(rows) > 100
    for name in seen[round(rows[0], 12)]:
        # the same numbers (the results rows evaluate the controller at the output times)
        np.testing.assert_allclose([seen[round(t, 12)][name] for t in rows],
                                   table.loc[rows, name], rtol=0, atol=1e-12)


def test_the_state_by_name():
    states = []
    casmech.analyze(compiled(PENDULUM, "0"), t_end=0.01,
                    controller=lambda t, s: states.append(s) or 0.0)
    state = states[0]
    assert "pivot.angle" in state and "bar.wz" in state and "bar.ax" not in state
    assert state.q.shape == (7,) and state.q_dot.shape == (7,)
    with pytest.raises(KeyError, match="not a state column"):
        state["bar.ax"]


@pytest.mark.parametrize("formulation", ["joint", "rp"])
@pytest.mark.parametrize(("law", "message"), [
    (lambda t, s: 1 / 0 if t > 0.5 else 0.0,
     r"analysis failed at t = 0\.5\d*: the controller .* raised ZeroDivisionError"),
    (lambda t, s: math.nan if t > 0.5 else 0.0,
     r"at t = 0\.5\d*: the controller .* returned a value that is not finite for pivot.torque"),
    (lambda t, s: {"elbow": 1.0} if t > 0.5 else 0.0,
     r"at t = 0\.5\d*: .* returned the key 'elbow', which is not one of the controlled motors "
     r"\(pivot.torque\)"),
    (lambda t, s: [1.0, 2.0] if t > 0.5 else 0.0,
     r"at t = 0\.5\d*: .* returned shape \(2,\); expected 1 number"),
    (lambda t, s: {} if t > 0.5 else 0.0, r"returned no value for pivot.torque"),
    (lambda t, s: "up" if t > 0.5 else 0.0, r"returned str, not a mapping of efforts"),
])
def test_a_faulty_controller_is_located_and_keeps_the_rows(formulation, law, message):
    with pytest.raises(AnalysisError, match=message) as raised:
        casmech.analyze(compiled(PENDULUM, "0"), formulation=formulation, controller=law)
    partial = raised.value.partial
    assert partial.status == "failed"
    times = np.array(partial.times)
    assert 0.3 < times[-1] <= 0.5 + 1e-12 and len(times) > 30
    frame = partial.to_dataframe()  # the rows before the fault tabulate
    assert np.all(np.isfinite(frame["pivot.angle"]))


@pytest.mark.parametrize(("arguments", "message"), [
    ({"controller": pd, "controls": ["hinge"]}, r"'hinge' is not an effort motor of the model; "
                                                r"effort motors: pivot.torque"),
    ({"controller": pd, "controls": ["pivot", "pivot.torque"]}, "given twice"),
    ({"controls": ["pivot"]}, "pass controller= too"),
    ({"controller": 3.0}, "controller must be callable"),
    ({"controller": pd, "analysis": "statics"}, "drives a dynamics run, not statics"),
])
def test_usage_errors(arguments, message):
    with pytest.raises(UsageError, match=message):
        casmech.analyze(compiled(PENDULUM, "0"), **arguments)


def test_a_model_without_an_effort_motor():
    model = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    with pytest.raises(UsageError, match=r"declare one on the controlled joint, e.g. "
                                         r"`motor: \{torque: 0\}`"):
        casmech.analyze(model, controller=pd)


def test_repeated_runs_and_an_earlier_result_keep_their_controller():
    """A second run with the same controller reuses the built functions and gives the same
    rows; a run with another controller leaves the first result's table (its reaction
    columns read the efforts) to the first controller."""
    free = compiled(PENDULUM, "0")
    times = []
    first = casmech.analyze(free, formulation="joint", controller=pd, progress=times.append)
    assert times == first.times
    again = casmech.analyze(free, formulation="joint", controller=pd)
    np.testing.assert_array_equal(again.q, first.q)  # the same functions, the same steps
    casmech.analyze(free, formulation="joint", controller=lambda t, s: {"pivot": 5.0})
    written = casmech.analyze(compiled(PENDULUM, PD), formulation="joint").to_dataframe()
    # the PD's reaction torque, to the integrator's tolerance
    np.testing.assert_allclose(first.to_dataframe()["pivot.ty"], written["pivot.ty"],
                               rtol=0, atol=1e-7)


@pytest.mark.slow
def test_a_compiled_model():
    """A compiled (parametric library) bundle: the controlled run is built over its IR at its
    values, after `set` too."""
    free = casmech.compile(casmech.loads(PENDULUM.replace("LAW", "0")), "compiled")
    heavier = free.set(kp=30.0)  # kp is read by no law here: the run is the callback's
    written = casmech.analyze(compiled(PENDULUM, PD), formulation="joint").to_dataframe()
    called = casmech.analyze(heavier, formulation="joint", controller=pd).to_dataframe()
    # two rtol 1e-10 integrations of one ODE
    np.testing.assert_allclose(called["pivot.angle"], written["pivot.angle"], rtol=0, atol=1e-7)
