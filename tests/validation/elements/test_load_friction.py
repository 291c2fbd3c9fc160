"""Joint friction with a load part (mu, mu_static, radius: equations/friction_load.py), a stuck
joint slipping at its located limit, and friction on screws, against closed forms written
here: a block on an incline, a disk on a horizontal axle, a torque ramp on a stuck disk and a
nut on a lead screw."""

from __future__ import annotations

import math

import numpy as np
import pytest

import casmech
from casmech.api import results_table
from casmech.errors import AnalysisError, ModelError

G = 9.81

INCLINE = """casmech: 1
name: incline
parameters: {{theta: {theta}, m: 2.0, g: 9.81}}
gravity: [0, 0, -g]
bodies:
  - {{name: block, mass: m, inertia: [0.1, 0.1, 0.1], position: [0, 0, 0]}}
joints:
  - name: slide
    type: {joint}
    body_i: ground
    body_j: block
    at: [0, 0, 0]
    axis: [cos(theta), 0, -sin(theta)]
    friction: {friction}
analysis: {{type: dynamics, t_end: 2.0, output_step: 0.01, rtol: 1.0e-10, atol: 1.0e-12,
           formulation: {formulation}}}
"""

M_DISK, J_DISK, R_AXLE, MU_AXLE = 3.0, 0.2, 0.02, 0.3
DISK = f"""casmech: 1
name: axle
gravity: [0, 0, -{G}]
bodies:
  - {{{{name: disk, mass: {M_DISK}, inertia: [0.1, {J_DISK}, 0.1], position: [0, 0, 0]}}}}
joints:
  - name: axle
    type: revolute
    body_i: ground
    body_j: disk
    at: [0, 0, 0]
    axis: [0, 1, 0]
    initial: {{{{angle: 0, angle_dot: {{w0}}}}}}
    friction: {{{{mu: {MU_AXLE}, radius: {R_AXLE}}}}}
{{forces}}
analysis: {{{{type: dynamics, t_end: 2.0, output_step: 0.01, rtol: 1.0e-10, atol: 1.0e-12,
           formulation: {{formulation}}}}}}
"""

M_NUT, J_NUT, LEAD = 0.5, 1e-4, 0.01
SCREW = f"""casmech: 1
name: lead_screw
gravity: [0, 0, -{G}]
bodies:
  - {{{{name: nut, mass: {M_NUT}, inertia: [0.0002, 0.0002, {J_NUT}], position: [0, 0, 0.3]}}}}
joints:
  - {{{{name: thread, type: screw, body_i: ground, body_j: nut, at: [0, 0, 0.3], axis: [0, 0, 1],
     lead: {LEAD}, friction: {{friction}}{{initial}}}}}}
analysis: {{{{type: dynamics, t_end: 1, output_step: 0.05, rtol: 1e-11, atol: 1e-12}}}}
"""


def run(text: str):
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions)
    names, values = results_table(functions, result)
    return result, dict(zip(names, values.T, strict=True))


@pytest.mark.parametrize("formulation", ["joint", "rp"])
@pytest.mark.parametrize("joint", ["translational", "cylindrical"])
def test_a_block_slides_down_an_incline_at_g_sin_minus_mu_cos(joint, formulation):
    theta, mu, m = 0.6, 0.5, 2.0
    result, columns = run(INCLINE.format(theta=theta, joint=joint, formulation=formulation,
                                         friction=f"{{mu: {mu}}}"))
    t = np.array(result.times)
    a = G * (math.sin(theta) - mu * math.cos(theta))
    assert a > 0
    # closed form s = a t^2 / 2 from rest, 1e-9 relative; atol: IDAS's (rp) absolute error
    # at atol 1e-12 over the first steps, some 3e-12
    np.testing.assert_allclose(columns["slide.displacement"], 0.5 * a * t ** 2, rtol=1e-9,
                               atol=1e-11)
    # the friction force is mu times the normal force m g cos(theta), against the motion
    np.testing.assert_allclose(columns["slide.friction"], -mu * m * G * math.cos(theta),
                               rtol=1e-10, atol=0)  # the law on the solved load: roundoff
    assert np.all(columns["slide.friction_mode"] == 1)
    assert result.metadata["friction_start_modes"] == {"slide": 1}  # released at the start


@pytest.mark.parametrize("formulation", ["joint", "rp"])
def test_a_block_within_its_static_cone_stays(formulation):
    """tan(theta) between mu and mu_static: Coulomb's static law holds it; it does not creep."""
    theta, mu, mu_static, m = 0.3, 0.2, 0.5, 2.0
    assert mu < math.tan(theta) < mu_static
    result, columns = run(INCLINE.format(
        theta=theta, joint="translational", formulation=formulation,
        friction=f"{{mu: {mu}, mu_static: {mu_static}}}"))
    assert np.max(np.abs(columns["slide.displacement"])) < 1e-9
    assert np.all(columns["slide.friction_mode"] == 0)
    # held by m g sin(theta) up the slope (the axis points down it)
    np.testing.assert_allclose(columns["slide.friction"], -m * G * math.sin(theta), rtol=1e-9,
                               atol=0)  # a multiplier, solved to roundoff
    assert result.metadata["friction_switches"] == []


def test_a_block_past_its_static_cone_slides_at_the_sliding_coefficient():
    """tan(theta) just above mu_static: it breaks away at once and slides with mu."""
    theta, mu, mu_static = 0.3, 0.2, 0.3
    assert mu_static < math.tan(theta)
    result, columns = run(INCLINE.format(theta=theta, joint="translational", formulation="rp",
                                         friction=f"{{mu: {mu}, mu_static: {mu_static}}}"))
    t = np.array(result.times)
    a = G * (math.sin(theta) - mu * math.cos(theta))
    # the closed form, integrated by IDAS at rtol 1e-10, atol 1e-12 (some 3e-12 absolute)
    np.testing.assert_allclose(columns["slide.displacement"], 0.5 * a * t ** 2, rtol=1e-9,
                               atol=1e-11)


@pytest.mark.parametrize("formulation", ["joint", "rp"])
def test_a_spinning_disk_on_an_axle_stops_by_radius_mu_m_g(formulation):
    """The bearing carries m g radially: the friction torque R mu m g decelerates the disk
    at R mu m g / J until it stops (at w0 J / (R mu m g)) and sticks there."""
    w0 = 1.5
    result, columns = run(DISK.format(w0=w0, forces="", formulation=formulation))
    torque = R_AXLE * MU_AXLE * M_DISK * G
    alpha = torque / J_DISK
    stop = w0 / alpha
    switches = result.metadata["friction_switches"]
    assert [s["mode"] for s in switches] == [0]
    # the located zero of the rate, to the run's tolerance (IDAS's rp a little looser)
    np.testing.assert_allclose(switches[0]["t"], stop, rtol=1e-8, atol=0)
    t = np.array(result.times)
    angle = np.where(t < stop, w0 * t - alpha * t ** 2 / 2, w0 ** 2 / (2 * alpha))
    # the closed form, integrated at rtol 1e-10 (rp's index-reduced DAE to some 1e-9)
    np.testing.assert_allclose(columns["axle.angle"], angle, rtol=0, atol=1e-8)
    sliding = columns["axle.friction_mode"] != 0
    np.testing.assert_allclose(columns["axle.friction"][sliding], -torque, rtol=1e-10,
                               atol=0)  # the law on the solved radial load: roundoff
    # stuck with nothing to hold: the holding torque is 0 (to the multipliers' roundoff)
    np.testing.assert_allclose(columns["axle.friction"][~sliding], 0, rtol=0, atol=1e-9)


@pytest.mark.parametrize("formulation", ["joint", "rp"])
def test_a_driven_disk_accelerates_by_its_torque_less_the_bearing_friction(formulation):
    torque = 0.5
    forces = f"forces:\n  - {{name: drive, type: torque, body: disk, value: [0, {torque}, 0]}}"
    result, columns = run(DISK.format(w0=0, forces=forces, formulation=formulation))
    t = np.array(result.times)
    alpha = (torque - R_AXLE * MU_AXLE * M_DISK * G) / J_DISK
    # the closed form (constant acceleration) integrated at rtol 1e-10
    np.testing.assert_allclose(columns["axle.angle_dot"], alpha * t, rtol=1e-9, atol=1e-8)
    assert result.metadata["friction_switches"] == []


def test_a_stuck_disk_slips_where_a_torque_ramp_reaches_the_static_limit():
    """T = k t on a disk held by friction (Ts 2, Tc 1): stuck until t* = Ts / k exactly (an
    event on the holding torque), then J w' = k t - Tc."""
    k, ts, tc, inertia = 4.0, 2.0, 1.0, 0.5
    text = f"""casmech: 1
name: ramp
gravity: [0, 0, 0]
bodies:
  - {{name: disk, mass: 1.0, inertia: [{inertia}, {inertia}, {inertia}], position: [0, 0, 0]}}
joints:
  - {{name: pivot, type: revolute, body_i: ground, body_j: disk, at: [0, 0, 0], axis: [0, 0, 1],
     friction: {{coulomb: {tc}, static: {ts}}}}}
forces:
  - {{name: drive, type: torque, body: disk, value: [0, 0, {k} * t]}}
analysis: {{type: dynamics, t_end: 1.0, output_step: 0.01, rtol: 1.0e-10, atol: 1.0e-12}}
"""
    result, columns = run(text)
    start = ts / k
    switches = result.metadata["friction_switches"]
    assert [s["mode"] for s in switches] == [1]
    # the located event, to the run's tolerance
    np.testing.assert_allclose(switches[0]["t"], start, rtol=1e-9, atol=0)
    t = np.array(result.times)
    rate = np.where(t < start, 0.0, (k / 2 * (t ** 2 - start ** 2) - tc * (t - start))
                    / inertia)
    # the closed form integrated at rtol 1e-10
    np.testing.assert_allclose(columns["pivot.angle_dot"], rate, rtol=0, atol=1e-8)
    stuck = t < start
    # held against the ramp: friction = -k t while stuck
    np.testing.assert_allclose(columns["pivot.friction"][stuck], -k * t[stuck], rtol=1e-9,
                               atol=1e-12)  # a multiplier, solved to roundoff


def test_a_nut_on_a_lead_screw_with_friction_falls_slower_by_the_friction_force():
    """a = (m g - Fc) / (m + J (2 pi / L)^2): the friction along the axis takes Fc of the
    weight (issue 32's screw closed form with Coulomb friction)."""
    fc = 1.0
    result, columns = run(SCREW.format(friction=f"{{coulomb: {fc}}}", initial=""))
    t = np.array(result.times)
    a = (M_NUT * G - fc) / (M_NUT + J_NUT * (2 * math.pi / LEAD) ** 2)
    # the closed form integrated at rtol 1e-11
    np.testing.assert_allclose(columns["thread.displacement"], -a * t ** 2 / 2, rtol=1e-9,
                               atol=1e-12)
    np.testing.assert_allclose(columns["thread.friction"], fc, rtol=1e-12, atol=0)  # the law


def test_a_nut_whose_weight_is_within_the_static_limit_stays():
    result, columns = run(SCREW.format(friction="{coulomb: 4.0, static: 5.0}", initial=""))
    assert M_NUT * G < 5.0
    assert np.max(np.abs(columns["thread.displacement"])) < 1e-9
    assert np.all(columns["thread.friction_mode"] == 0)
    # the friction holds the weight along the axis (z up)
    np.testing.assert_allclose(columns["thread.friction"], M_NUT * G, rtol=1e-9,
                               atol=0)  # a multiplier, solved to roundoff


@pytest.mark.parametrize(("joint", "friction", "expected"), [
    ("revolute", "{mu: 0.3}", ("E100", "joints[0].friction")),
    ("translational", "{mu: 0.3, radius: 0.1}", ("E103", "joints[0].friction.radius")),
    ("cylindrical", "{mu: 0.3, mu_static: 0.2}", ("E103", "joints[0].friction.mu_static")),
    ("translational", "{mu: -0.1}", ("E103", "joints[0].friction.mu")),
    ("revolute", "{mu: 0.1, radius: -1}", ("E103", "joints[0].friction.radius")),
    ("revolute", "{coulomb: 1, radius: 1 kg}", ("E205", "joints[0].friction.radius")),
])
def test_bad_load_friction_is_located(joint, friction, expected):
    text = INCLINE.format(theta=0.3, joint=joint, formulation="auto", friction=friction)
    with pytest.raises(ModelError) as raised:
        casmech.loads(text)
    found = [(d.code, d.path) for d in raised.value.diagnostics]
    assert found == [expected]
    assert raised.value.diagnostics[0].source.line == 14  # the friction's line


def test_a_screw_refuses_a_load_part_at_its_key():
    text = SCREW.format(friction="{coulomb: 1, mu: 0.2}", initial="")
    with pytest.raises(ModelError) as raised:
        casmech.loads(text)
    assert [(d.code, d.path) for d in raised.value.diagnostics] == [
        ("E103", "joints[0].friction.mu")]


def rough_pendulum(formulation: str, friction: str, initial: str = "") -> str:
    """A bar on a horizontal pivot released level: its bearing's radial load changes with its
    swing and with the friction torque itself (the load's response n1 is not 0)."""
    return f"""casmech: 1
name: rough_pendulum
gravity: [0, 0, -{G}]
bodies:
  - {{name: bar, mass: 1.0, inertia: [0.02, 0.02, 0.02], position: [0.5, 0, 0]}}
joints:
  - {{name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 1, 0],
     friction: {friction}{initial}}}
analysis: {{type: dynamics, t_end: 3.0, output_step: 0.01, rtol: 1.0e-10, atol: 1.0e-12,
           formulation: {formulation}}}
"""


def test_a_pendulums_bearing_friction_is_radius_mu_times_its_reported_radial_force():
    """At every sliding row the friction torque is -sign (Tc + R mu |F_radial|) with F the
    reaction columns (the multipliers the run solved): the implicit law holds exactly in the
    joint formulation, to IDAS's algebraic tolerance in rp; the two switch alike."""
    tc, mu, radius = 0.01, 0.3, 0.05
    friction = f"{{coulomb: {tc}, mu: {mu}, radius: {radius}}}"
    runs = {}
    for formulation, rtol in (("joint", 1e-12), ("rp", 1e-7)):
        result, columns = run(rough_pendulum(formulation, friction))
        mode = columns["pivot.friction_mode"]
        radial = np.hypot(columns["pivot.fx"], columns["pivot.fz"])  # the axis is y
        sliding = mode != 0
        assert sliding.sum() > 250
        # joint: one solve of the same equations (roundoff); rp: the DAE's lam is solved to
        # IDAS's tolerance, the law's load from (q, q_dot)
        np.testing.assert_allclose(columns["pivot.friction"][sliding],
                                   -mode[sliding] * (tc + mu * radius * radial[sliding]),
                                   rtol=rtol, atol=0)
        runs[formulation] = result.metadata["friction_switches"]
        assert len(runs[formulation]) == 3
    # two formulations of the same motion: switch times to the runs' tolerance
    np.testing.assert_allclose([s["t"] for s in runs["rp"]], [s["t"] for s in runs["joint"]],
                               rtol=1e-8, atol=0)


def test_a_friction_that_would_lock_its_joint_by_itself_is_an_analysis_error():
    """mu R m e / J_o >= 1 (here 0.6 * 1 * 0.5 / 0.27 = 1.11): Painleve's paradox."""
    text = rough_pendulum("joint", "{mu: 0.6, radius: 1.0}", ", initial: {angle_dot: 2}")
    functions = casmech.compile(casmech.loads(text))
    with pytest.raises(AnalysisError) as raised:
        casmech.analyze(functions)
    message = str(raised.value)
    assert "Painleve" in message and "'pivot'" in message
    assert "1.11" in message  # the measure named beside the joint
