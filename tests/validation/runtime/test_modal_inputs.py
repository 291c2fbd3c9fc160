"""Force elements as inputs of the linear model (`analysis: {type: modal, inputs: [...]}`,
runtime/linearize.py) against closed forms and against the effort-motor inputs."""

import numpy as np

import casmech
from tests.helpers.statics_models import HANGING_ROD, RSDA_PENDULUM, SPRING_MASS, G


def linear_model(text: str, inputs: str, at: str = ""):
    head, _, _ = text.rpartition("\nanalysis:")
    text = head + f"\nanalysis: {{type: modal, inputs: [{inputs}]{at}}}\n"
    functions = casmech.compile(casmech.loads(text))
    return casmech.analyze(functions).linear_model


def output_acceleration(model, output: str) -> np.ndarray:
    """d(output'')/du: C = [C_z, 0], so the output's acceleration per unit input is C_z B_w."""
    k = model.basis.shape[1]
    return model.C[model.output_names.index(output), :k] @ model.B[k:]


def test_spring_force_input_accelerates_the_block_by_one_over_m():
    m = 3.0  # SPRING_MASS: the spring from the origin to the block at x = 1 + p/k
    model = linear_model(SPRING_MASS, "spring, push")
    assert model.input_names == ["spring.force", "push.fx", "push.fy", "push.fz"]
    # a tension u pulls the block towards the origin: -1/m; the push along x: +1/m; y and z
    # are carried by the slide. Closed forms of a 1-DOF oscillator: rtol 1e-12
    np.testing.assert_allclose(output_acceleration(model, "block.dx"),
                               [-1 / m, 1 / m, 0, 0], rtol=1e-12, atol=1e-15)


def test_spring_force_input_dc_gain_with_python_control():
    import control

    k = 120.0
    system = linear_model(SPRING_MASS, "spring, push").state_space()
    gain = control.dcgain(system)
    row = system.output_labels.index("block_dx")
    # static deflection u / k (a tension shortens the spring), python-control's own solve of
    # -C A^-1 B: rtol 1e-10
    np.testing.assert_allclose(gain[row, :2], [-1 / k, 1 / k], rtol=1e-10, atol=0)


def test_spring_input_at_a_time_of_the_run_is_the_same_column():
    # B of the spring's force does not depend on the state along the slide: at t = 0.4 of the
    # oscillation the column is -1/m again (rtol 1e-10: a run at the default tolerances moves
    # the spring's direction not at all, it stays along x)
    m = 3.0
    model = linear_model(SPRING_MASS, "spring", ", at: 0.4")
    assert model.t == 0.4
    np.testing.assert_allclose(output_acceleration(model, "block.dx"), [-1 / m], rtol=1e-10,
                               atol=0)


ROD_WITH_MOTOR_AND_TORQUE = HANGING_ROD.replace(
    "axis: [0, 1, 0]}", "axis: [0, 1, 0],\n     motor: {torque: \"0\"}}").replace("""
analysis:""", """
forces:
  - {name: twist, type: torque, body: rod, value: [0, 0, 0]}
  - {name: twist_body, type: torque, body: rod, value: [0, 0, 0], frame: body}
analysis:""")


def test_torque_element_input_is_the_motor_input_about_the_hinge():
    model = linear_model(ROD_WITH_MOTOR_AND_TORQUE, "pivot, twist, twist_body")
    names = model.input_names
    assert names == ["pivot.torque", "twist.tx", "twist.ty", "twist.tz",
                     "twist_body.tx", "twist_body.ty", "twist_body.tz"]
    # a torque about global y on the rod is the motor's torque about the hinge (axis +y);
    # about x and z the revolute carries it; in the rod's body frame (turned 0 at the
    # equilibrium: hanging, body axes global) the same. Roundoff on entries O(1): atol 1e-12
    column = model.B[:, names.index("pivot.torque")]
    np.testing.assert_allclose(model.B[:, names.index("twist.ty")], column, rtol=0, atol=1e-12)
    np.testing.assert_allclose(model.B[:, names.index("twist_body.ty")], column, rtol=0,
                               atol=1e-12)
    for name in ("twist.tx", "twist.tz", "twist_body.tx", "twist_body.tz"):
        np.testing.assert_allclose(model.B[:, names.index(name)], 0.0, rtol=0, atol=1e-12)
    # the rod's static rotation per unit torque: 1 / (m g l) (the motor test's closed form)
    m, length = 1.5, 0.8
    gain = -model.C @ np.linalg.solve(model.A, model.B)
    np.testing.assert_allclose(gain[model.output_names.index("rod.ry"), names.index("twist.ty")],
                               1 / (m * G * length / 2), rtol=1e-10, atol=0)


def test_rsda_torque_input_opposes_the_angle():
    text = RSDA_PENDULUM.replace("axis: [0, 1, 0]}",
                                 "axis: [0, 1, 0],\n     motor: {torque: \"0\"}}")
    model = linear_model(text, "spring, pivot")
    assert model.input_names == ["spring.torque", "pivot.torque"]
    # the rsda's tension turns body j back: minus the motor's torque about the same angle
    np.testing.assert_allclose(model.B[:, 0], -model.B[:, 1], rtol=0, atol=1e-12)
    assert np.max(np.abs(model.B[:, 1])) > 0.1


BUSHED_BLOCK = """
casmech: 1
name: bushed_block
parameters: {kx: 2000.0, ky: 3000.0, kz: 5000.0, kr: 70.0}
gravity: [0, 0, 0]
bodies:
  - {name: block, mass: 4.0, inertia: [0.05, 0.06, 0.07], position: [0, 0, 0]}
forces:
  - {name: mount, type: bushing, body_i: ground, body_j: block, at: [0, 0, 0],
     stiffness: [kx, ky, kz], rotational_stiffness: [kr, 2 * kr, 3 * kr]}
analysis: {type: modal}
"""


def test_bushing_input_static_gains_are_one_over_its_stiffnesses():
    model = linear_model(BUSHED_BLOCK, "mount")
    names = model.input_names
    assert names == [f"mount.{c}" for c in ("fx", "fy", "fz", "tx", "ty", "tz")]
    gain = -model.C @ np.linalg.solve(model.A, model.B)
    kx, ky, kz, kr = 2000.0, 3000.0, 5000.0, 70.0
    outputs = [model.output_names.index(f"block.{c}") for c in ("dx", "dy", "dz", "rx", "ry", "rz")]
    # the bushing at the CM, global axes, no gravity: decoupled, deflection u / k in each of
    # its six directions (the force on body_j, as its preload); 6 x 6 solve: rtol 1e-10
    np.testing.assert_allclose(gain[np.ix_(outputs, range(6))],
                               np.diag(1 / np.array([kx, ky, kz, kr, 2 * kr, 3 * kr])),
                               rtol=1e-10, atol=1e-14)


def test_b_at_a_time_of_a_run_matches_finite_differences_of_the_actuator():
    """A moving four-bar (redundant revolutes, r-p DAE) with a tsda strut whose `actuator:` is a
    parameter u0: B's column of strut.force against central differences in u0 of the chart's
    ODE (tests/validation/runtime/test_modal_at.chart_ode, casmech's own numerics) at the run's
    state."""
    from tests.helpers.statics_models import HANGING_FOUR_BAR
    from tests.validation.runtime.test_modal_at import at_time, chart_ode

    text = HANGING_FOUR_BAR.replace("  m: 1.0\n", "  m: 1.0\n  u0: 0.0\n").replace("""
analysis:""", """
forces:
  - {name: strut, type: tsda, body_i: coupler, at_i: [Cx, 0, Cz], body_j: ground,
     at_j: [0.4, 0, 0.6], stiffness: 30, damping: 2, actuator: u0}
analysis:""")
    text = at_time(text, 0.3, ", inputs: [strut]")
    model = casmech.analyze(casmech.compile(casmech.loads(text))).linear_model
    assert model.input_names == ["strut.force"]
    eps = 1e-4
    x = np.concatenate([np.zeros(model.basis.shape[1]), model.basis.T @ model.q_dot])
    sides = [chart_ode(casmech.compile(casmech.loads(text, overrides={"u0": repr(u)})),
                       model.t, model.q, model.basis, x) for u in (eps, -eps)]
    # the ODE is affine in u0: central differences exact but for roundoff ~1e-15 / eps on
    # accelerations O(10) (measured 1e-11 on an entry of 0.18): atol 1e-9
    np.testing.assert_allclose(model.B[:, 0], (sides[0] - sides[1]) / (2 * eps), rtol=0,
                               atol=1e-9)
    assert np.max(np.abs(model.B[:, 0])) > 0.01
