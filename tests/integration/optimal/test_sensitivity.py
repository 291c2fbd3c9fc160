"""Exact IDAS sensitivities (forward and adjoint) against central finite differences.

The finite differences re-load the model with `--set`-style overrides, so they go through the
whole numeric pipeline (schema, plain lowering, compile) instead of the traced lowering and
its d(theta) under test.
"""


import numpy as np
import pytest

import casmech
from casmech.errors import UsageError
from casmech.optimal.sensitivity import sensitivity, simulate
from tests.conftest import MODELS

PENDULUM = MODELS / "estimate_pendulum.yaml"

# 3D: a bar on a spherical joint carries a second bar on a revolute joint; a spring-damper pulls
# the second bar towards a ground point off the plane; gravity, masses, inertia, spring and an
# initial angular velocity are parameters.
MECHANISM = """
casmech: 1
name: spatial_chain
parameters:
  g: 9.81
  m1: 1.5
  m2: 0.8
  J: 0.04
  k: 30.0
  c: 0.4
  w0: 1.2
gravity: [0, 0, -g]
bodies:
  - {name: upper, mass: m1, inertia: [J, J, 0.01], position: [0.3, 0, -0.4],
     orientation: {x_axis: [0.6, 0, -0.8], y_axis: [0, 1, 0]}, angular_velocity: [0, 0, w0]}
  - {name: lower, mass: m2, inertia: [0.02, 0.03, 0.01], position: [0.6, 0.25, -0.8]}
joints:
  - {name: shoulder, type: spherical, body_i: ground, body_j: upper, at: [0, 0, 0]}
  - {name: elbow, type: revolute, body_i: upper, body_j: lower, at: [0.6, 0, -0.8],
     axis: [0.8, 0, 0.6]}
forces:
  - {name: spring, type: tsda, body_i: ground, at_i: [0.5, 0.8, 0.2], body_j: lower,
     at_j: [0.6, 0.5, -0.8], stiffness: k, damping: c}
"""

TIGHT = {"rtol": 1e-12, "atol": 1e-14}  # finite differences need the integrator far below h^4
# the 4-link spherical chain fails IDAS's corrector at rtol 1e-12: rtol 1e-10, h^4 at h = 3e-3
# is 1e-10, solver noise / h up to ~1e-7 (measured agreement 7e-8 for L, 3e-7 for w0)
LOOSE = {"tight": {"rtol": 1e-10, "atol": 1e-12}}


def central_difference(load, name, value, outputs, times, step, tight=TIGHT):
    """Fourth-order central differences of full simulations of re-loaded models (steps +-h,
    +-2h): truncation h^4 instead of the h^2 that needed tolerances of 1e-5. Also what the
    simulations' own error puts into them, per output column: each end is within
    rtol |y| + atol of its exact value where IDAS's error test holds the output to that, and
    the stencil's weights (8 + 8 + 1 + 1) / 12 carry that over h, so a structurally zero
    derivative reads as up to that much; a reaction, a function of the multipliers, carries
    more (measured 2.4e-10 N at rtol 3e-12 on a reaction of 1 N), so the error of the
    differences is measured too: their distance from the same differences at 2h (steps +-2h,
    +-4h), whose truncation is 16x and whose noise half of theirs."""
    ends = {k: simulate(load({name: repr(value + k * step)}), outputs, times, **tight)
            for k in (-4, -2, -1, 1, 2, 4)}
    size = np.max([np.abs(end) for end in ends.values()], axis=(0, 1))
    noise = 1.5 * (tight["rtol"] * size + tight["atol"]) / step

    def differences(k: int):
        return (8 * (ends[k] - ends[-k]) - (ends[2 * k] - ends[-2 * k])) / (12 * k * step)

    found = differences(1)
    return found, noise + np.abs(found - differences(2)).max(axis=0)


def check(load, parameters, outputs, times, tight=TIGHT, tolerance=1e-6, **options):
    """Forward and adjoint sensitivities against one set of central differences."""
    model = load({})
    results = [sensitivity(model, parameters, outputs, times, mode=m, **options)
               for m in ("forward", "adjoint")]
    for j, name in enumerate(parameters):
        value = model.parameters[name]
        fd, noise = central_difference(load, name, value, outputs, times,
                                       3e-3 * (abs(value) or 1.0), tight)
        bound = tolerance * np.abs(fd).max(axis=0) + noise
        for result in results:
            # relative 1e-6 of each output column's size (the bound) plus what the
            # simulations' error puts into the differences (h = 3e-3 relative, IDAS at rtol
            # 1e-12: h^4 truncation ~1e-10 relative); a structurally zero column is zero to
            # that noise, which no solver's differences get below (measured 1e-12 with the
            # saddle solve by QR and by LU, on either side of zero)
            np.testing.assert_allclose(result.jacobian[..., j] / bound, fd / bound, rtol=0,
                                       atol=1)
    return results


def test_pendulum_parameters():
    def load(overrides):
        return casmech.load(PENDULUM, overrides)

    check(load, ["m", "c"], ["bar.y", "bar.z", "bar.wx", "pivot.fz", "energy"], [0.4, 1.0])


def test_spatial_mechanism():
    """gravity and inertia (applied by linearity), a spring, an initial angular velocity."""
    def load(overrides):
        return casmech.loads(MECHANISM, overrides=overrides)

    check(load, ["g", "J", "k", "w0"],
          ["lower.x", "lower.y", "lower.z", "upper.wz", "elbow.fy", "energy"], [0.15, 0.3])


def test_forward_and_adjoint_agree():
    model = casmech.loads(MECHANISM)
    names, outputs = ["m2", "k"], ["lower.vz", "shoulder.fz"]
    forward, adjoint = (sensitivity(model, names, outputs, [0.5], mode=m)
                        for m in ("forward", "adjoint"))
    # two different IDAS sweeps, each at rtol 1e-10: measured agreement 2e-10 relative
    np.testing.assert_allclose(forward.jacobian, adjoint.jacobian, rtol=1e-6, atol=1e-9)


def test_initial_velocity_sensitivity_of_a_conserved_energy():
    """Without damping the energy is conserved, so its derivative with respect to an initial
    velocity is the same at every time (here against t = 1e-6, where it is the initial one)."""
    model = casmech.loads(MECHANISM, overrides={"c": "0"})
    later = sensitivity(model, ["upper.wz", "w0"], ["energy"], [0.2, 0.5], mode="adjoint")
    start = sensitivity(model, ["upper.wz", "w0"], ["energy"], [1e-6])
    # energy drifts by ~1e-9 at IDAS rtol 1e-10: its derivatives agree (measured 8e-11)
    np.testing.assert_allclose(later.jacobian[:, 0, :], np.repeat(start.jacobian[:, 0, :], 2, 0),
                               rtol=1e-6, atol=1e-8)
    # an offset of upper.wz and the parameter w0 (upper's wz in the file) are the same thing
    np.testing.assert_allclose(start.jacobian[0, 0, 0], start.jacobian[0, 0, 1], rtol=1e-12,
                               atol=1e-12)  # identical graphs up to rounding


def test_usage_errors():
    model = casmech.load(PENDULUM)
    with pytest.raises(UsageError, match="neither a parameter"):
        sensitivity(model, ["nope"], ["bar.y"], [0.5])
    with pytest.raises(UsageError, match="unknown output column"):
        sensitivity(model, ["m"], ["bar.q"], [0.5])
    with pytest.raises(UsageError, match="mode 'reverse' is not one of"):
        sensitivity(model, ["m"], ["bar.y"], [0.5], mode="reverse")


def test_driver_parameter_with_degrees_of_freedom():
    """An elbow driver A sin(3t) + A on the 3D chain (2 DOF left): assembly moves the pose
    along the path its Newton iterations take, which the unrolled assembly graph reproduces."""
    text = MECHANISM.replace("  w0: 1.2\n", "  w0: 1.2\n  A: 0.3\n").replace(
        "axis: [0.8, 0, 0.6]}", "axis: [0.8, 0, 0.6],\n     driver: {angle: A * sin(3*t) + A}}")

    def load(overrides):
        return casmech.loads(text, overrides=overrides)

    check(load, ["A"], ["lower.x", "lower.z", "upper.wz", "elbow.fy"], [0.2, 0.4])


def test_integral_outputs():
    """integral(COLUMN) is an IDAS quadrature: without damping the energy is constant, so its
    integral is E(0) t (closed form); its derivatives match central differences."""
    def load(overrides):
        return casmech.load(PENDULUM, {"c": "0", **overrides})

    outputs = ["integral(energy)", "integral(bar.y)", "integral(pivot.fz)"]
    check(load, ["m"], outputs, [0.5, 1.0])
    model = load({})
    result = sensitivity(model, ["m"], outputs, [0.5, 1.0])
    start = simulate(model, ["energy"], [1e-9])[0, 0]
    # energy is conserved to IDAS's rtol 1e-10 (measured drift of the integral ~1e-10)
    np.testing.assert_allclose(result.values[:, 0], start * np.array([0.5, 1.0]), rtol=1e-8,
                               atol=1e-10)


def test_fully_driven_arm_forward_and_adjoint():
    """0 DOF (models/robot_arm_3r.yaml: three driven joints): the motion is prescribed, so a
    mass changes only the driving torques and a driver amplitude changes both. IDAS used to
    fail at t = 0 on this model in both modes (error test on the algebraic states)."""
    def load(overrides):
        return casmech.load(MODELS / "robot_arm_3r.yaml", overrides)

    check(load, ["m2", "A2"], ["shoulder.ty", "forearm.z"], [1.0])


EFFORT_MOTOR = """
casmech: 1
name: pushed_slider
parameters: {F: 2.0, m: 0.5}
gravity: [0, 0, 0]
bodies:
  - {name: slider, mass: m, inertia: [0.01, 0.01, 0.01], position: [0, 0, 0]}
joints:
  - {name: rail, type: translational, body_i: ground, body_j: slider, at: [0, 0, 0],
     axis: [1, 0, 0], motor: {force: F}}
"""


def test_parameter_only_in_an_effort_motor():
    """x = F t^2 / (2 m) on a rail pushed by a force motor: dx/dF = t^2 / (2 m),
    dx/dm = -F t^2 / (2 m^2), with F used nowhere but in the motor."""
    model = casmech.loads(EFFORT_MOTOR)
    times = np.array([0.5, 1.0])
    want = np.stack([times**2 / (2 * 0.5), -2.0 * times**2 / (2 * 0.5**2)], axis=-1)
    for mode in ("forward", "adjoint"):
        result = sensitivity(model, ["F", "m"], ["slider.x"], times, mode=mode)
        # IDAS at the default rtol 1e-10 on a polynomial motion: measured 1e-13 relative
        np.testing.assert_allclose(result.jacobian[:, 0, :], want, rtol=1e-8, atol=1e-10)


def test_adjoint_of_a_free_fall():
    """z = -g t^2 / 2: dz/dg = -t^2 / 2 (a single free body, gravity a parameter). CasADi's
    reverse mode with respect to an integrator's parameters gave -0.580 at t = 1
    (sensitivity._parameters_as_states says why and how casmech avoids it)."""
    model = casmech.loads("""
casmech: 1
name: fall
parameters: {g: 2.0}
gravity: [0, 0, -g]
bodies:
  - {name: b, mass: 0.5, inertia: [0.01, 0.01, 0.01], position: [0, 0, 0]}
""")
    times = np.array([0.5, 1.0])
    for mode in ("forward", "adjoint"):
        result = sensitivity(model, ["g"], ["b.z"], times, mode=mode)
        # closed form; both modes meet it to 1e-13 (a quadratic motion: BDF is exact)
        np.testing.assert_allclose(result.jacobian[:, 0, 0], -times**2 / 2, rtol=1e-9,
                                   atol=1e-12)


def test_composed_model():
    """A composed model (components, repeat): its parameters pass through the instances'
    values and placements as traced numbers; a repeat count is structure, a located usage
    error."""
    path = MODELS / "chain_repeat.yaml"

    def load(overrides):
        return casmech.load(path, overrides)

    model = load({})
    check(load, ["L", "w0"], ["link2.bar.z", "j2.fz"], [0.15], **LOOSE)
    line = 1 + model.text[:model.text.index("  N: 4")].count("\n")
    with pytest.raises(UsageError, match=rf"chain_repeat.yaml:{line}:3: parameter 'N' cannot be "
                                         r"a variable: .*repeat bound cannot depend on a "
                                         r"symbolic parameter \(N\)"):
        sensitivity(model, ["N"], ["link2.bar.z"], [0.15])


def test_pendulum_length_and_initial_angle():
    """A pendulum's length L (its position, its joint point in the bar's frame, the same
    number in both) and its initial angle a0 (an initial orientation): geometry, through the
    model data; the angle (e1 = sin(angle / 2)) and the positions at t."""
    def load(overrides):
        return casmech.load(PENDULUM, overrides)

    check(load, ["L", "a0"], ["bar.e1", "bar.y", "bar.z", "pivot.fz", "energy"], [0.5, 1.0])


# A four-bar whose coupler is a massless distance link of fixed length 2 between the crank's tip
# and the rocker's tip at (cx, 1.47808): moving cx moves that joint point on the rocker, the
# file's pose no longer closes the loop, and assembly moves the crank and the rocker (the
# sensitivity runs through the assembly's dependence on cx). Gravity in the plane; 1 DOF.
FOUR_BAR = """
casmech: 1
name: four_bar_distance
parameters:
  cx: 1.74452
gravity: [0, -9.81, 0]
bodies:
  - {name: crank, mass: 1.0, inertia: [0.0003, 0.021, 0.021], position: [0, 0.25, 0],
     orientation: {axis_angle: {axis: [0, 0, 1], angle: 1.5708}}}
  - {name: rocker, mass: 1.2, inertia: [0.0003, 0.19, 0.19], position: [1.87226, 0.73904, 0],
     orientation: {axis_angle: {axis: [0, 0, 1], angle: 1.74195}}}
joints:
  - {name: crank_pivot, type: revolute, body_i: ground, body_j: crank, at: [0, 0, 0],
     axis: [0, 0, 1]}
  - {name: coupler, type: distance, body_i: crank, body_j: rocker, at_i: [0, 0.5, 0],
     at_j: [cx, 1.47808, 0], length: 2.0}
  - {name: rocker_pivot, type: revolute, body_i: ground, body_j: rocker, at: [2, 0, 0],
     axis: [0, 0, 1]}
"""


def test_four_bar_joint_point_through_assembly():
    def load(overrides):
        return casmech.loads(FOUR_BAR, overrides=overrides)

    outputs = ["crank.x", "crank.wz", "rocker.y", "rocker_pivot.fx", "coupler.fx", "energy"]
    forward, _ = check(load, ["cx"], outputs, [1e-6, 0.3, 0.6])
    # the assembled pose moves with cx (d crank.x / d cx at t = 0 is ~0.1): the derivative
    # checked above includes the assembly's
    assert abs(forward.jacobian[0, 0, 0]) > 0.05


# the spatial chain with its elbow axis turned by an angle (no entry of the axis in either
# body's frame is zero, so the structure stays as it is while the angle moves)
TILTED = MECHANISM.replace("  w0: 1.2\n", "  w0: 1.2\n  tilt: 0.5\n").replace(
    "axis: [0.8, 0, 0.6]}", "axis: [cos(tilt), 0.3, sin(tilt)]}")


def test_axis_angle_and_joint_point_of_a_spatial_chain():
    def load(overrides):
        return casmech.loads(TILTED, overrides=overrides)

    check(load, ["tilt", "k"], ["lower.x", "lower.z", "upper.wz", "elbow.fy"], [0.2, 0.4])


def test_numbers_that_are_zero_at_the_value_move_with_it():
    """At tilt = atan2(0.6, 0.8) the elbow axis is perpendicular to the upper bar's x axis: a
    zero in upper's frame that any other tilt makes non-zero; at a0 = 0 the pendulum's
    position has a zero y that L and a0 move. Both are traced numbers, entries of d(theta),
    so the derivatives hold there too (the differences re-load the plain models at the moved
    values, whose zeros are gone)."""
    text = TILTED.replace("tilt: 0.5", "tilt: atan2(0.6, 0.8)")
    check(lambda overrides: casmech.loads(text, overrides=overrides), ["tilt"],
          ["lower.x", "lower.z", "elbow.fy"], [0.2])
    check(lambda overrides: casmech.load(PENDULUM, {"a0": "0", "c": "0", **overrides}),
          ["L", "a0"], ["bar.y", "bar.z", "pivot.fz"], [0.5])
