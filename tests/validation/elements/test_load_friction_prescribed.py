"""Joint friction's load part in prescribed motion (kinematics, inverse dynamics;
formulations/prescribed_friction.py): the load solved together with the multipliers, against
closed forms written here (a driven block on an incline, pressed by a known force; a rotor
spun about a horizontal axle) and against a dynamics run of the same motion (a slider-crank
whose slider friction's load depends on the rod's force, the crank torque of inverse dynamics
fed back as an effort motor)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import casmech
from casmech.api import results_table
from casmech.errors import AnalysisError
from tests.helpers.friction_models import (
    ANGLE0,
    CRANK_DRIVER,
    MU,
    TC,
    THETA,
    W0,
    C,
    G,
    M,
    W,
    driven_incline,
    driven_rotor,
    slider_crank,
)

INCLINE = driven_incline("0.3*t + 0.2*sin(3*t)",
                         "FORCESanalysis: {type: ANALYSIS, t_end: 2.0, output_step: 0.01}\n")


def run(text: str, path=None, options=None):
    model = casmech.loads(text) if path is None else casmech.load(path)
    functions = casmech.compile(model)
    result = casmech.analyze(functions, options=options)
    names, values = results_table(functions, result)
    return result, dict(zip(names, values.T, strict=True))


def along(columns, joint: str, axis, kind: str = "f") -> np.ndarray:
    return sum(axis[k] * columns[f"{joint}.{kind}{c}"] for k, c in enumerate("xyz"))


@pytest.mark.parametrize(("analysis", "options"), [
    ("inverse_dynamics", None), ("kinematics", None),
    ("inverse_dynamics", {"pivot_ratio": 1.0})])  # every row by the per-row code
@pytest.mark.parametrize("press", [0.0, 15.0])
def test_a_driven_block_on_an_incline_needs_m_a_minus_m_g_sin_plus_its_friction(press,
                                                                                analysis,
                                                                                options):
    """The driver's force along the slide: m s_ddot - m g sin(theta) - f, with the friction
    f = -sign(s_dot) (Tc + mu (m g cos(theta) + P)) - c s_dot, P a force pressing the block
    onto the slope (normal to it, into it); the rate crosses 0, where the friction is 0."""
    normal = np.array([math.sin(THETA), 0.0, math.cos(THETA)])  # out of the slope
    forces = "" if press == 0 else (
        "forces:\n  - {name: press, type: force, body: block, "
        f"value: [{-press * normal[0]}, 0, {-press * normal[2]}]}}\n")
    result, columns = run(INCLINE.replace("FORCES", forces).replace("ANALYSIS", analysis),
                          options=options)
    assert result.metadata["per_row_rows"] == (len(result) if options else 0)
    t = np.array(result.times)
    rate, acceleration = 0.3 + 0.6 * np.cos(3 * t), -1.8 * np.sin(3 * t)
    assert np.any(rate > 0) and np.any(rate < 0)
    load = M * G * math.cos(THETA) + press
    friction = -np.sign(rate) * (TC + MU * load) - C * rate
    # the law on the solved load: roundoff of a few terms of size m g
    np.testing.assert_allclose(columns["slide.friction"], friction, rtol=1e-12, atol=1e-12)
    # the driver's force along the slide, closed form; rtol 1e-9 relative to its scale
    np.testing.assert_allclose(along(columns, "slide", W),
                               M * acceleration - M * G * math.sin(THETA) - friction,
                               rtol=0, atol=1e-9 * M * G)


ROTOR = driven_rotor("{type: inverse_dynamics, t_end: 1.0, output_step: 0.01}")


@pytest.mark.parametrize("speed", [4.0, -4.0, 0.0])
def test_a_rotor_spun_about_a_horizontal_axle_needs_tc_plus_mu_radius_m_g(speed):
    """The bearing carries m g radially at any constant rate: the torque holding the rate is
    sign(w) (Tc + mu radius m g); at rest (w = 0) no friction, as the sliding law says."""
    result, columns = run(ROTOR.replace("SPEED", repr(speed)))
    torque = math.copysign(0.05 + 0.3 * 0.02 * 3.0 * G, speed) if speed else 0.0
    # the actuation about the axle (y): closed form, to roundoff of terms of size m g radius
    np.testing.assert_allclose(columns["axle.ty"], torque, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(columns["axle.friction"], -torque, rtol=1e-9, atol=1e-14)


def over_a_second(crank: str, analysis: str) -> str:
    """The slider-crank over 1 s: the crank turns from 0.3 to 2.8 rad when driven, so the
    slider moves one way throughout."""
    return slider_crank(crank, analysis, 1.0, 0.001)


def test_a_slider_crank_torque_from_inverse_dynamics_drives_the_same_motion(tmp_path):
    """Inverse dynamics with both loads (the slide's depends on the rod's force, which its
    friction changes; the crank bearing's on the rod's force too); its crank torque, as a
    cubic table on an effort motor, makes a dynamics run follow the driven crank angle."""
    driven = CRANK_DRIVER
    result, columns = run(over_a_second(driven, "inverse_dynamics"))
    t = np.array(result.times)
    # the frictions are the laws on the reactions the multipliers give (solved together)
    slide_rate = columns["slide.displacement_dot"]
    assert np.all(slide_rate < 0)
    normal = np.hypot(columns["slide.fy"], columns["slide.fz"])
    # the law evaluated on the written columns: roundoff of forces of some 30 N
    np.testing.assert_allclose(columns["slide.friction"], 0.3 * normal - 0.1 * slide_rate,
                               rtol=1e-12, atol=1e-12)
    radial = np.hypot(columns["crank_pivot.fx"], columns["crank_pivot.fy"])
    np.testing.assert_allclose(columns["crank_pivot.friction"], -(0.05 + 0.2 * 0.02 * radial),
                               rtol=1e-12, atol=1e-12)  # as above
    table = tmp_path / "torque.csv"
    np.savetxt(table, np.column_stack([t, columns["crank_pivot.tz"]]), delimiter=",",
               header="t,torque", comments="")
    motor = (f"motor: {{torque: {{table: torque.csv, column: torque}}}}, "
             f"initial: {{angle: {ANGLE0}, angle_dot: {W0}}}")
    path = tmp_path / "forward.yaml"
    path.write_text(over_a_second(motor, "dynamics"))
    forward, replay = run(None, path)
    assert forward.metadata["friction_switches"] == []  # both slide throughout
    # the same motion: the torque's cubic spline (h = 1 ms) and IDAS at rtol 1e-11 over 1 s
    np.testing.assert_allclose(replay["crank_pivot.angle"], ANGLE0 + W0 * np.array(forward.times),
                               rtol=0, atol=1e-6)
    # and the same slide friction (its load from the dynamics run's own coupled solve)
    np.testing.assert_allclose(replay["slide.friction"],
                               np.interp(forward.times, t, columns["slide.friction"]),
                               rtol=0, atol=1e-6)  # as above, in newtons


def test_a_friction_that_could_lock_its_joint_is_a_located_analysis_error():
    """mu times the change of the slide's load per unit friction force (the rod's slope,
    here up to some 0.13) reaching 1: no unique load, as in a dynamics run (Painleve)."""
    text = over_a_second(CRANK_DRIVER, "inverse_dynamics")
    with pytest.raises(AnalysisError, match="Painleve") as raised:
        run(text.replace("mu: 0.3", "mu: 10.0"))
    assert "joint 'slide'" in str(raised.value)
    assert raised.value.partial is not None
