"""Motors (equations/motors.py, schema/motors.py) against closed forms of driven rigid bodies.

Speed mode: a rod pendulum turned at a prescribed speed under gravity; the angle rate equals the
speed and the motor torque equals the inverse-dynamics closed form J_O theta'' + m g L/2 cos theta
(derived in `rod_torque`). Torque mode: a disc on a vertical axis (gravity has no moment about
it) under a constant torque (theta = T t^2 / 2J), a linear spring-like torque -k theta
(harmonic, period 2 pi sqrt(J/k)) and a rate-dependent one (first-order spin-up). Force mode: a
slider under a constant force. Position mode equals the same motion written as `driver:`.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

import casmech
from casmech.errors import ModelError
from tests.conftest import Table

M, L, W = 3.0, 0.8, 0.04  # rod mass [kg], length [m], cross-section [m]
G = 9.81
J_DISC = 0.25  # disc moment of inertia about its axis [kg m^2]


def rod(motor: str, analysis: str = "dynamics") -> str:
    """A rod lying along +y from a pivot at the origin, revolute about global x, gravity -z."""
    return f"""
casmech: 1
name: rod
parameters: {{m: {M}, L: {L}, w: {W}}}
bodies:
  - name: bar
    mass: m
    inertia: [m * (L**2 + w**2) / 12, m * w**2 / 6, m * (L**2 + w**2) / 12]
    position: [0, L/2, 0]
joints:
  - name: pivot
    type: revolute
    body_i: ground
    body_j: bar
    at: [0, 0, 0]
    axis: [1, 0, 0]
    {motor}
analysis: {{type: {analysis}, t_end: 2, output_step: 0.05, rtol: 1e-12, atol: 1e-14}}
"""


def disc(motor: str, spin: float = 0.0, extra: str = "") -> str:
    """A disc on a vertical revolute axis through its centre (no gravity moment about it)."""
    return f"""
casmech: 1
name: disc
bodies:
  - {{name: disc, mass: 2, inertia: [0.2, 0.2, {J_DISC}], position: [0, 0, 0],
     angular_velocity: [0, 0, {spin}]}}
joints:
  - {{name: pivot, type: revolute, body_i: ground, body_j: disc, at: [0, 0, 0], axis: [0, 0, 1],
     motor: {motor}}}
{extra}
analysis: {{type: dynamics, t_end: 1, output_step: 0.05, rtol: 1e-10, atol: 1e-12}}
"""


MOTOR_LINE = rod("motor: X").splitlines().index("    motor: X") + 1


def run(text: str, **settings) -> Table:
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions, **settings)
    return Table(*casmech.results_table(functions, result))


def rod_angle(table: Table) -> np.ndarray:
    """The rod's rotation about +x from +y, from its CM (independent of casmech's angle)."""
    return np.unwrap(np.arctan2(table["bar.z"], table["bar.y"]))


def rod_torque(theta, theta_ddot):
    """Moment about the pivot axis the motor must apply: Euler about the fixed pivot O,
    J_O theta'' = tau + (moment of gravity about x) = tau - m g (L/2) cos(theta), with
    J_O = m (L^2 + w^2) / 12 + m (L/2)^2 (parallel axes; the CM is L/2 from O)."""
    j_o = M * (L**2 + W**2) / 12 + M * (L / 2) ** 2
    return j_o * theta_ddot + M * G * (L / 2) * np.cos(theta)


# ---------------------------------------------------------------------------------- speed
@pytest.mark.parametrize("speed, rate, acceleration", [
    ("2*pi", lambda t: 2 * np.pi + 0 * t, lambda t: 0 * t),
    ("2 + 3*cos(4*t) - t**2", lambda t: 2 + 3 * np.cos(4 * t) - t**2,
     lambda t: -12 * np.sin(4 * t) - 2 * t),
], ids=["constant", "varying"])
def test_speed_motor_holds_its_speed_under_gravity(speed, rate, acceleration):
    table = run(rod(f'motor: {{speed: "{speed}"}}'))
    t = table["t"]
    # the angle is a position-level constraint (the exact integral): the rate holds to IDAS's
    # tolerances without drift; measured max deviation 6.8e-10 (constant), 2.7e-10 (varying)
    np.testing.assert_allclose(table["bar.wx"], rate(t), rtol=0, atol=1e-9)
    # angle from positions vs the integral of the speed; measured 1e-13
    theta = rod_angle(table)
    integral = [quad(rate, 0, s, epsabs=1e-13, epsrel=1e-13)[0] for s in t]
    np.testing.assert_allclose(theta, integral, rtol=1e-9, atol=1e-9)
    # the motor torque is the joint's reaction about the axis; against the closed form: measured
    # up to 4e-6 N m of 11.8 at a few outputs (the multipliers solved at each row's state, whose
    # positions and rates carry the integrator's error)
    np.testing.assert_allclose(table["pivot.tx"], rod_torque(theta, acceleration(t)),
                               rtol=0, atol=2e-5)


def test_speed_motor_torque_by_inverse_dynamics():
    table = run(rod('motor: {speed: "2 + 3*cos(4*t) - t**2"}', "inverse_dynamics"))
    t = table["t"]
    theta = 2 * t + 0.75 * np.sin(4 * t) - t**3 / 3  # the integral of the speed, by hand
    # position-level exactness: Newton converges to 1e-12; measured 2e-16 rad
    np.testing.assert_allclose(rod_angle(table), theta, rtol=0, atol=1e-10)
    # accelerations and multipliers solved exactly at each time: measured 1.2e-12 N m
    np.testing.assert_allclose(table["pivot.tx"], rod_torque(theta, -12 * np.sin(4 * t) - 2 * t),
                               rtol=0, atol=1e-9)


def test_constant_speed_torque_is_m_g_l_half_cos_theta():
    omega = 2.0
    table = run(rod(f"motor: {{speed: {omega}}}"))
    theta = omega * table["t"]
    # theta'' = 0: the motor only holds the rod against gravity; measured up to 4e-6 N m of 11.8
    # (the multipliers are IDAS algebraic states; inverse dynamics below checks to 1e-9)
    np.testing.assert_allclose(table["pivot.tx"], M * G * L / 2 * np.cos(theta), rtol=0,
                               atol=2e-5)


def test_position_motor_equals_the_same_driver():
    expression = "pi/3 * sin(2*t)"
    by_motor = run(rod(f'motor: {{angle: "{expression}"}}', "kinematics"))
    by_driver = run(rod(f'driver: {{angle: "{expression}"}}', "kinematics"))
    # the same row of phi: identical up to Newton's last iterate (measured 0)
    np.testing.assert_allclose(by_motor.values, by_driver.values, rtol=1e-12, atol=1e-12)


# --------------------------------------------------------------------------------- torque
def disc_angle(table: Table) -> np.ndarray:
    """Rotation about z from the Euler parameters (p = [cos a/2, 0, 0, sin a/2])."""
    return np.unwrap(2 * np.arctan2(table["disc.e3"], table["disc.e0"]))


def test_constant_torque_spins_the_disc_up_quadratically():
    torque = 3.0
    table = run(disc(f"{{torque: {torque}}}"))
    t = table["t"]
    # theta = T t^2 / 2J, omega = T t / J: IDAS at rtol 1e-10, measured 3.3e-9 rad of 6 and
    # 4.3e-8 rad/s of 12
    np.testing.assert_allclose(disc_angle(table), torque * t**2 / (2 * J_DISC), rtol=1e-8,
                               atol=1e-9)
    np.testing.assert_allclose(table["disc.wz"], torque * t / J_DISC, rtol=1e-8, atol=1e-9)
    # the revolute's reaction includes the actuation; its own rows add ~0 about z (measured 2e-9
    # from the multipliers at rtol 1e-10)
    np.testing.assert_allclose(table["pivot.tz"], torque, rtol=0, atol=1e-8)


def test_linear_torque_is_a_harmonic_oscillator():
    k, spin = 4.0, 1.5
    table = run(disc(f'{{torque: "-{k}*angle"}}', spin), t_end=2.0, output_step=0.01)
    frequency = math.sqrt(k / J_DISC)
    t = table["t"]
    theta = disc_angle(table)
    # theta = (w0 / w) sin(w t): amplitude 0.375 rad stays inside atan2's (-pi, pi]; measured
    # 1.3e-9 rad
    np.testing.assert_allclose(theta, spin / frequency * np.sin(frequency * t), rtol=1e-8,
                               atol=1e-8)
    # period from the zero crossings (linear interpolation on a 0.01 s grid: error < 1e-4 s)
    crossings = [t[i] - theta[i] * (t[i + 1] - t[i]) / (theta[i + 1] - theta[i])
                 for i in range(1, len(t) - 1) if theta[i] * theta[i + 1] < 0]
    np.testing.assert_allclose(2 * np.diff(crossings), 2 * np.pi * math.sqrt(J_DISC / k),
                               rtol=1e-4, atol=0)
    np.testing.assert_allclose(table["pivot.tz"], -k * theta, rtol=1e-7, atol=1e-8)


def test_rate_dependent_torque_spins_up_to_its_limit():
    table = run(disc('{torque: "5 - 0.5*angle_dot"}'))
    t = table["t"]
    # J w' = 5 - 0.5 w, w(0) = 0: w = 10 (1 - exp(-0.5 t / J)); measured 2.3e-8 rad/s
    np.testing.assert_allclose(table["disc.wz"], 10 * (1 - np.exp(-0.5 * t / J_DISC)),
                               rtol=1e-8, atol=1e-8)


def test_viscous_torque_is_reported_in_the_reaction_from_the_rate():
    c, spin = 0.5, 4.0
    table = run(disc(f'{{torque: "-{c}*angle_dot"}}', spin))
    assert not np.isnan(table.values).any()
    # J w' = -c w: w = w0 exp(-c t / J), the motion (independent of the reaction); measured
    # 1.3e-9 rad/s of 4
    np.testing.assert_allclose(table["disc.wz"], spin * np.exp(-c * table["t"] / J_DISC),
                               rtol=1e-8, atol=1e-8)
    # the reaction about the axis is the motor law at the reported rate (was NaN without q_dot);
    # the revolute's own rows add ~0 about z: measured 6.7e-16 N m of 2, so absolute only
    np.testing.assert_allclose(table["pivot.tz"], -c * table["disc.wz"], rtol=0, atol=1e-12)


def test_constant_force_accelerates_the_slider():
    text = """
casmech: 1
name: slider
bodies: [{name: block, mass: 4, inertia: [1, 1, 1], position: [0, 0, 0]}]
joints:
  - {name: slide, type: translational, body_i: ground, body_j: block, at: [0, 0, 0],
     axis: [1, 1, 0], motor: {force: 2}}
analysis: {type: dynamics, t_end: 1, output_step: 0.1, rtol: 1e-10, atol: 1e-12}
"""
    table = run(text)
    t = table["t"]
    along = (table["block.x"] + table["block.y"]) / math.sqrt(2)
    # s = F t^2 / 2m along the axis (gravity -z is perpendicular to it); measured 1e-11
    np.testing.assert_allclose(along, 2 * t**2 / 8, rtol=1e-8, atol=1e-10)
    # the joint's force on the block along the axis is the motor's 2 N
    force = (table["slide.fx"] + table["slide.fy"]) / math.sqrt(2)
    np.testing.assert_allclose(force, 2.0, rtol=1e-10, atol=1e-9)


def test_cylindrical_motor_drives_both_motions():
    text = """
casmech: 1
name: screw
bodies: [{name: nut, mass: 1, inertia: [0.1, 0.1, 0.05], position: [0, 0, 0]}]
joints:
  - {name: axle, type: cylindrical, body_i: ground, body_j: nut, at: [0, 0, 0], axis: [0, 0, 1],
     motor: {speed: 3, force: 9.81}}
analysis: {type: dynamics, t_end: 1, output_step: 0.1, rtol: 1e-12, atol: 1e-14}
"""
    table = run(text)
    # speed 3 rad/s held (measured 3e-10 at rtol 1e-12); the force 9.81 N on 1 kg cancels
    # gravity along z: the nut stays put
    np.testing.assert_allclose(table["nut.wz"], 3.0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(table["nut.z"], 0.0, rtol=0, atol=1e-9)


# --------------------------------------------------------------------------------- errors
def diagnostics(text: str):
    with pytest.raises(ModelError) as error:
        casmech.loads(text)
    return error.value.diagnostics


@pytest.mark.parametrize("motor, code, words, hint", [
    ("{omega: 3}", "E101", "unknown motor key 'omega'", "angle | speed | torque"),
    ("{velocity: 3}", "E408", "velocity motor is not allowed", "angle | speed | torque"),
    ("{speed: 1, torque: 2}", "E408", "one mode per motion", "angle | speed | torque"),
    ("{speed: 'sqrt(1 + t)'}", "E204", "no closed-form integral", "angle:"),
    ("{speed: '2*t*sin(t)'}", "E204", "no closed-form integral", "angle:"),
    ("{}", "E408", "needs a mode", "angle | speed | torque"),
], ids=["unknown", "mismatched", "two-modes", "sqrt", "product", "empty"])
def test_bad_motors_are_located_errors(motor, code, words, hint):
    found = diagnostics(rod(f"motor: {motor}"))
    assert [d.code for d in found] == [code]
    assert words in found[0].message and hint in found[0].hint
    assert found[0].source.line == MOTOR_LINE


def test_no_closed_form_points_at_the_part():
    text = rod("motor: {speed: '1 + sqrt(t)'}")
    found = diagnostics(text)
    line = text.splitlines()[MOTOR_LINE - 1]
    assert found[0].source.line == MOTOR_LINE
    assert found[0].source.col == line.index("sqrt") + 1
    assert found[0].got == "sqrt(t)"


def test_motor_and_driver_on_the_same_motion_conflict():
    found = diagnostics(rod("driver: {angle: t}\n    motor: {speed: 1}"))
    assert [d.code for d in found] == ["E408"] and "both driver and motor" in found[0].message


def test_motor_on_a_spherical_joint_is_refused():
    text = rod("motor: {torque: 1}").replace("type: revolute", "type: spherical")
    text = text.replace("    axis: [1, 0, 0]\n", "")
    found = diagnostics(text)
    assert [d.code for d in found] == ["E408"]
    # the hint names the joint types with a coordinate (casmech.elements.joint_types)
    assert found[0].hint == "motors act on revolute, cylindrical, translational and screw joints"
