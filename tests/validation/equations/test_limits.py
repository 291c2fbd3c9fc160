"""Joint limits (equations/limits.py) against closed forms: a pendulum released onto a revolute
stop (the quarter period by the complete elliptic integral, the contact a half oscillation of
the stop's stiffness plus gravity's, the rebound back to the release angle), a slider held on a
translational stop (static penetration F / k, the energy bound on the overshoot), and the
stop's force in the joint's reaction columns."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import ellipk

import casmech

G, L, M = 9.81, 1.0, 1.0
I_PIVOT = M * L**2 / 3  # a slender bar about its end
K_STOP = 1e4

PENDULUM = """
casmech: 1
name: stop_pendulum
gravity: [0, -9.81, 0]
bodies:
  - {{name: bar, mass: 1, inertia: [1e-4, 0.08333333333333333, 0.08333333333333333],
     position: [0.5, 0, 0]}}
joints:
  - name: pivot
    type: revolute
    body_i: ground
    body_j: bar
    at: [0, 0, 0]
    axis: [0, 0, 1]
    limit: {{lower: {lower}, stiffness: {k}, damping: {c}}}
analysis: {{type: dynamics, t_end: {t_end}, output_step: 1e-4, rtol: 1e-11, atol: 1e-13}}
"""


def run(text: str, **options):
    functions = casmech.compile(casmech.loads(text))
    return casmech.analyze(functions, **options).to_dataframe()


def crossings(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Times where y changes sign, by linear interpolation between rows."""
    k = np.nonzero(np.sign(y[:-1]) != np.sign(y[1:]))[0]
    return t[k] + y[k] * (t[k + 1] - t[k]) / (y[k] - y[k + 1])


@pytest.fixture(scope="module")
def released():
    """Released horizontal onto an undamped stop at the bottom (-pi/2 about +z)."""
    return run(PENDULUM.format(lower=-np.pi / 2, k=K_STOP, c=0, t_end=1.2))


def test_pendulum_reaches_the_stop_at_the_quarter_period(released):
    omega = np.sqrt(M * G * L / 2 / I_PIVOT)
    quarter = ellipk(np.sin(np.pi / 4) ** 2) / omega  # from horizontal to the bottom
    hits = crossings(released.index.to_numpy(), released["pivot.limit_gap"].to_numpy())
    # linear interpolation of the gap on the 1e-4 s grid: (theta'' dt^2 / 8) / theta' ~ 1e-9 s
    np.testing.assert_allclose(hits[0], quarter, rtol=0, atol=1e-6)
    # in contact: I d'' = -(k + m g L/2) d to first order in the overshoot d (< 0.04 rad; the
    # cubic term changes the half period by ~ (m g L/2 / k) d^2 ~ 1e-7): half a period of it
    half = np.pi * np.sqrt(I_PIVOT / (K_STOP + M * G * L / 2))
    np.testing.assert_allclose(hits[1] - hits[0], half, rtol=1e-5, atol=0)


def test_pendulum_rebounds_to_its_release_angle(released):
    after = released[released.index > 0.7]
    # undamped stop: energy conserved, so it swings back to horizontal (gap pi/2); the peak on
    # the 1e-4 s grid misses the apex by (theta'' dt^2 / 8) ~ 1e-8 rad; integration ~1e-9
    np.testing.assert_allclose(after["pivot.limit_gap"].max(), np.pi / 2, rtol=0, atol=1e-6)
    energy = released["energy"].to_numpy()
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-7)  # integration error


def test_damped_stop_dissipates_and_the_reaction_holds_the_stops_torque():
    result = run(PENDULUM.format(lower=-np.pi / 2, k=K_STOP, c=50.0, t_end=3.0))
    energy = result["energy"].to_numpy()
    assert np.max(np.diff(energy)) < 1e-8  # never gains energy (integration error only)
    # the stop torque enters the revolute's reaction tz at every row, through the impacts (an
    # ideal revolute transmits no torque about its axis): equal to rounding of ~100 N m
    assert result["pivot.limit_torque"].max() > 50  # it hit the stop
    np.testing.assert_allclose(result["pivot.tz"], result["pivot.limit_torque"], rtol=0,
                               atol=1e-9)


HELD = """
casmech: 1
name: held_pendulum
gravity: [0, -9.81, 0]
bodies:
  - {name: bar, mass: 1, inertia: [1e-4, 0.08333333333333333, 0.08333333333333333],
     position: [0.5, 0, 0]}
joints:
  - name: pivot
    type: revolute
    body_i: ground
    body_j: bar
    at: [0, 0, 0]
    axis: [0, 0, 1]
    limit: {lower: 0, upper: 1, stiffness: 1e4, damping: 100}
analysis: {type: dynamics, t_end: 2.0, output_step: 1e-3, rtol: 1e-10, atol: 1e-12}
"""


def test_a_stop_holds_a_horizontal_pendulum_with_its_static_penetration():
    end = run(HELD).iloc[-1]
    # equilibrium k d = m g L/2 cos(d) (gravity's arm shrinks as the bar dips by d): fixed point
    d = 0.0
    for _ in range(20):
        d = M * G * L / 2 * np.cos(d) / 1e4
    # settled (damping 100 N m s over 2 s): static equilibrium to far below 1e-8
    np.testing.assert_allclose(end["pivot.limit_torque"], 1e4 * d, rtol=1e-8, atol=0)
    np.testing.assert_allclose(end["pivot.tz"], 1e4 * d, rtol=1e-8, atol=0)
    np.testing.assert_allclose(end["pivot.limit_gap"], -d, rtol=1e-8, atol=0)


SLIDER = """
casmech: 1
name: slider_stop
gravity: [0, 0, 0]
bodies:
  - {{name: block, mass: 2, inertia: [0.1, 0.1, 0.1], position: [0, 0, 0]}}
joints:
  - name: rail
    type: {joint}
    body_i: ground
    body_j: block
    at: [0, 0, 0]
    axis: [1, 0, 0]
    limit: {{lower: -0.1, upper: 0.2, stiffness: 1e5, damping: {c}}}
forces:
  - {{name: push, type: force, body: block, value: [30, 0, 0]}}
analysis: {{type: dynamics, t_end: {t_end}, output_step: 1e-4, rtol: 1e-10, atol: 1e-12}}
"""


@pytest.mark.parametrize("joint", ["translational", "cylindrical"])
def test_slider_stays_inside_its_limit(joint):
    result = run(SLIDER.format(joint=joint, c=0, t_end=1.0))
    x = result["block.x"].to_numpy()
    # undamped: it arrives at 0.2 with 1/2 m v^2 = F 0.2 and stops where the stop's energy
    # 1/2 k d^2 takes F (0.2 + d) (energy, exact): the largest overshoot
    k, f = 1e5, 30.0
    d = (f + np.sqrt(f**2 + 2 * k * f * 0.2)) / k
    # the 1e-4 s grid samples the peak within a dt^2 / 8 = 7e-7 m (a = k d / m = 560 m/s^2)
    np.testing.assert_allclose(x.max(), 0.2 + d, rtol=0, atol=1e-6)
    assert x.min() > -0.1 - 1e-12  # never through the lower stop (it bounces back to 0)


def test_slider_rests_on_the_stop_with_the_reaction_of_the_pushing_force():
    end = run(SLIDER.format(joint="translational", c=2000, t_end=1.0)).iloc[-1]
    # settled on the upper stop: static penetration F / k (exact for a linear stop)
    np.testing.assert_allclose(end["block.x"], 0.2 + 30 / 1e5, rtol=1e-9, atol=0)
    np.testing.assert_allclose(end["rail.limit_force"], -30.0, rtol=1e-9, atol=0)
    np.testing.assert_allclose(end["rail.limit_gap"], -30 / 1e5, rtol=1e-6, atol=0)
    # the joint's reaction on the block includes the stop's push back along the axis
    np.testing.assert_allclose(end["rail.fx"], -30.0, rtol=1e-9, atol=0)


MOTORED = """
casmech: 1
name: motored_stop
gravity: [0, -9.81, 0]
bodies:
  - {name: bar, mass: 1, inertia: [1e-4, 0.0833, 0.0833], position: [0.5, 0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 0, 1],
     motor: {torque: "2 * sin(t)"}, limit: {lower: -1.2, upper: 0.3, stiffness: 1e4, damping: 20}}
analysis: {type: dynamics, t_end: 1.0, output_step: 0.01, rtol: 1e-10, atol: 1e-12}
"""


@pytest.mark.parametrize("text", [SLIDER.format(joint="translational", c=2000, t_end=0.3),
                                  MOTORED], ids=["slider", "motor_and_stop"])
def test_compiled_mode_equals_interpreted(text, quick_builds):
    model = casmech.loads(text)
    results = [casmech.analyze(casmech.compile(model, mode), formulation="rp").to_dataframe()
               for mode in ("interpreted", "compiled")]
    assert list(results[0].columns) == list(results[1].columns)
    # the same equations in C: round-off grown by the integration (rtol 1e-10) through the
    # stop's impacts (measured 2.5e-4 absolute on up to 176 N m at rtol 1e-8)
    np.testing.assert_allclose(results[1].to_numpy(), results[0].to_numpy(), rtol=1e-5,
                               atol=1e-5)
