"""Inputs of an FMU: an effort motor's torque, and an `ocp:` control, driven through fmpy,
against `casmech run` of the same model whose motor law is the same function of time."""

import numpy as np
import pytest

import casmech
from tests.helpers.fmu import (
    MODELS,
    STEP,
    T_END,
    assert_matches,
    build,
    outputs,
    reference,
    simulate,
)
from tests.helpers.fmu import (
    slave as instance,
)

PENDULUM = """
casmech: 1
name: motor_pendulum
parameters:
  L: 0.8
  m: 1.2
  k0: 0.5     # motor torque at t = 0 [N m]
  k1: 2.0     # its rate [N m/s]
gravity: [0, 0, -9.81]
bodies:
  - name: bar
    mass: m
    inertia: [m * L**2 / 12, m * L**2 / 12, 1.0e-4]
    position: [L/2, 0, 0]
joints:
  - name: hinge
    type: revolute
    body_i: ground
    body_j: bar
    at: [0, 0, 0]
    axis: [0, 1, 0]
    motor: {torque: "k0 + k1 * t"}
analysis: {type: dynamics, t_end: 1, output_step: 0.01}
"""


def pendulum(**values):
    return casmech.loads(PENDULUM, "motor_pendulum.yaml",
                         {name: str(value) for name, value in values.items()})


@pytest.fixture(scope="module")
def fmu(toolchain, tmp_path_factory):
    return build(pendulum(), tmp_path_factory.mktemp("fmu"), toolchain, "motor_pendulum")


def test_the_motor_is_an_input_starting_at_its_law(fmu):
    from fmpy import read_model_description

    inputs = [v for v in read_model_description(str(fmu)).modelVariables
              if v.causality == "input"]
    assert [(v.name, float(v.start)) for v in inputs] == [("hinge.torque", 0.5)]


def ramp(fmu, derivative: bool, tmp_path) -> dict[str, float]:
    """Co-Simulation through fmpy's FMU2Slave, the input 0.5 + 2 t set at every communication
    point, with its derivative (fmi2SetRealInputDerivatives: the FMU interpolates it linearly
    within the step) or without (held over the step). fmpy's simulate_fmu cannot give
    derivatives of fewer than 9 inputs (0.3.32: a fixed array of 9)."""
    slave, refs = instance(fmu, tmp_path)
    slave.setupExperiment(tolerance=1e-10, startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    steps = round(T_END / STEP)
    for k in range(steps):
        t = k * STEP
        slave.setReal([refs["hinge.torque"]], [0.5 + 2.0 * t])
        if derivative:
            slave.setRealInputDerivatives([refs["hinge.torque"]], [1], [2.0])
        slave.doStep(t, STEP)
    names = outputs(fmu)
    values = dict(zip(names, slave.getReal([refs[n] for n in names]), strict=True))
    slave.terminate()
    slave.freeInstance()
    return values


def test_a_ramp_given_with_its_derivative_drives_it_as_the_law_does(fmu, tmp_path):
    got = ramp(fmu, True, tmp_path / "with")
    assert_matches(got, reference(pendulum()))
    held = ramp(fmu, False, tmp_path / "without")  # piecewise constant: off by O(STEP)
    assert abs(held["bar.x"] - got["bar.x"]) > 1e-5


@pytest.mark.parametrize("kind", ("ModelExchange", "CoSimulation"))
def test_a_constant_input_replaces_the_law(fmu, kind):
    signal = np.array([(0.0, 1.7), (T_END, 1.7)],
                      dtype=[("time", float), ("hinge.torque", float)])
    assert_matches(simulate(fmu, kind, input=signal), reference(pendulum(k0=1.7, k1=0.0)))


def test_an_ocp_control_is_an_input(toolchain, tmp_path):
    """The swing-up's control on `pivot` (no motor in the file): an input starting at 0;
    a constant 1.5 N m moves the pendulum as a motor with that law does."""
    text = (MODELS / "ocp_pendulum_swing_up.yaml").read_text()
    model = casmech.loads(text, str(MODELS / "ocp_pendulum_swing_up.yaml"))
    fmu = build(model, tmp_path, toolchain, "swing_up")
    from fmpy import read_model_description

    inputs = [(v.name, float(v.start)) for v in read_model_description(str(fmu)).modelVariables
              if v.causality == "input"]
    assert inputs == [("pivot.torque", 0.0)]
    driven = text.replace("    axis: [1, 0, 0]\n", "    axis: [1, 0, 0]\n    motor: {torque: "
                          '"1.5"}\n', 1)
    assert driven != text
    signal = np.array([(0.0, 1.5), (T_END, 1.5)], dtype=[("time", float),
                                                          ("pivot.torque", float)])
    expected = reference(casmech.loads(driven, str(MODELS / "ocp_pendulum_swing_up.yaml")))
    assert_matches(simulate(fmu, "ModelExchange", input=signal), expected)
