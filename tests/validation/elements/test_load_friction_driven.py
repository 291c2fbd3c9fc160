"""Joint friction's load part on a driven coordinate in a dynamics run
(runtime/driven_friction.py): the driver's actuation and the friction column against closed
forms written here (a block driven along an incline; a rotor spun about a horizontal axle), in
every formulation, and against inverse dynamics of the same motion (a slider-crank driven at
its crank, whose slide friction's load is solved in the run's sliding segment)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import casmech
from casmech.api import results_table
from tests.helpers.friction_models import (
    CRANK_DRIVER,
    MU,
    TC,
    THETA,
    C,
    G,
    M,
    W,
    driven_incline,
    driven_rotor,
    slider_crank,
)

INCLINE = driven_incline("SIGN * (0.3*t + 0.05*sin(3*t))", """events:
  - {name: halfway, when: "t - 0.55"}
analysis: {type: dynamics, t_end: 1.0, output_step: 0.02, rtol: 1.0e-11, atol: 1.0e-12}
""")


def run(text: str, formulation: str | None = None):
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions, formulation=formulation)
    names, values = results_table(functions, result)
    return functions, result, dict(zip(names, values.T, strict=True))


def along(columns, joint: str, axis, kind: str = "f") -> np.ndarray:
    return sum(axis[k] * columns[f"{joint}.{kind}{c}"] for k, c in enumerate("xyz"))


@pytest.mark.parametrize(("formulation", "sign"),
                         [("rp", 1.0), ("romega", -1.0), ("joint", 1.0), ("joint", -1.0)])
def test_a_block_driven_along_an_incline_needs_its_load_part_in_every_formulation(formulation,
                                                                                 sign):
    """The driver's force along the slide is m s_ddot - m g sin(theta) - f with the friction
    f = -sign(s_dot) (Tc + mu m g cos(theta)) - c s_dot (up the slope: m a + m g sin(theta)
    + Tc + mu m g cos(theta) + c |s_dot|); the rate never reaches 0. The event's row too."""
    _, result, columns = run(INCLINE.replace("SIGN", repr(sign)), formulation)
    assert result.metadata["formulation"] == formulation
    t = np.array(result.times)
    rate, acceleration = sign * (0.3 + 0.15 * np.cos(3 * t)), sign * -0.45 * np.sin(3 * t)
    friction = -sign * (TC + MU * M * G * math.cos(THETA)) - C * rate
    # the law on the row's load: the integrated rate's error (rtol 1e-6 of a DAE) times c
    np.testing.assert_allclose(columns["slide.friction"], friction, rtol=1e-9, atol=0)
    # the driver's force along the slide, closed form, 1e-9 of its scale m g
    np.testing.assert_allclose(along(columns, "slide", W),
                               M * acceleration - M * G * math.sin(THETA) - friction,
                               rtol=0, atol=1e-9 * M * G)
    # the event's row (events.csv) as the rows: the same closed form at t = 0.55
    event = result.events_dataframe().iloc[0]
    at = event["t"]
    assert event["name"] == "halfway"
    np.testing.assert_allclose(at, 0.55, rtol=0, atol=1e-9)  # located to the run's tolerance
    expected = (M * sign * -0.45 * math.sin(3 * at) - M * G * math.sin(THETA)
                + sign * (TC + MU * M * G * math.cos(THETA) + C * (0.3 + 0.15 * math.cos(3 * at))))
    np.testing.assert_allclose(sum(W[k] * event[f"slide.f{c}"] for k, c in enumerate("xyz")),
                               expected, rtol=0, atol=1e-9 * M * G)  # as the rows


ROTOR = driven_rotor(
    "{type: dynamics, t_end: 1.0, output_step: 0.05, rtol: 1.0e-11, atol: 1.0e-12}")


@pytest.mark.parametrize(("formulation", "speed"),
                         [("rp", 4.0), ("romega", -4.0), ("joint", 4.0), ("joint", 0.0)])
def test_a_rotor_spun_about_a_horizontal_axle_needs_tc_plus_mu_radius_m_g(formulation, speed):
    """The bearing carries m g radially at any constant rate: the driver's torque is
    sign(w) (Tc + mu radius m g), the friction its opposite; at rest no friction."""
    _, _, columns = run(ROTOR.replace("SPEED", repr(speed)), formulation)
    torque = math.copysign(0.05 + 0.3 * 0.02 * 3.0 * G, speed) if speed else 0.0
    # closed form; the multipliers to 1e-8 of the largest reaction (m g) in every formulation
    # (solved at each row's state, which carries the integrator's error)
    np.testing.assert_allclose(columns["axle.ty"], torque, rtol=0, atol=1e-8 * 3.0 * G)
    # the law on the row's load: roundoff of the rows' reaction m g
    np.testing.assert_allclose(columns["axle.friction"], -torque, rtol=1e-9, atol=1e-12)


def driven_slider_crank(analysis: str) -> str:
    """The slider-crank with its crank driven at a constant rate, over 0.25 s."""
    return slider_crank(CRANK_DRIVER, analysis, 0.25, 0.01)


@pytest.fixture(scope="module")
def inverse():
    return run(driven_slider_crank("inverse_dynamics"))[2]


@pytest.mark.parametrize("formulation", [
    "joint", pytest.param("romega", marks=pytest.mark.slow)])
def test_a_driven_slider_crank_needs_the_torque_inverse_dynamics_gives(inverse, formulation):
    """The dynamics run of the driven crank: its torque and every joint's reaction and
    friction are inverse dynamics' of the same motion (the crank bearing's load depends on
    the rod's force, which the slide's friction changes; the slide's load is the segment's)."""
    _, result, columns = run(driven_slider_crank("dynamics"), formulation)
    assert result.metadata["formulation"] == formulation
    assert np.all(columns["slide.displacement_dot"] < 0)  # the slide slides throughout
    names = ("crank_pivot.tz", "crank_pivot.friction", "crank_pivot.fx", "crank_pivot.fy",
             "slide.friction", "slide.fy", "slide.fz")
    scale = max(np.max(np.abs(inverse[name])) for name in names)
    for name in names:
        # the integrated motion at rtol 1e-11 against the prescribed one: 1e-8 of the largest
        np.testing.assert_allclose(columns[name], inverse[name], rtol=0, atol=1e-8 * scale,
                                   err_msg=name)
