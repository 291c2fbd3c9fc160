"""Assembly: positions from the file's pose, drivers reached by continuation, velocities
projected onto the constraints, accelerations and reactions from the equations of motion."""

import numpy as np
import pytest

import casmech
from casmech.errors import AnalysisError
from tests.conftest import MODELS, Table

M, L, G, I_CM = 2.0, 1.2, 9.81, 0.3  # mass, CM distance from the pivot, gravity, inertia about x


def pendulum(theta0=0.0, omega0=0.0, driver=None, extra_joint="", file_velocity=None):
    """A pendulum about global x at the origin, CM at distance L, drawn at angle theta0."""
    r = [0.0, L * np.sin(theta0), -L * np.cos(theta0)]
    v = file_velocity or [0.0, L * np.cos(theta0) * omega0, L * np.sin(theta0) * omega0]
    r, v = ([float(x) for x in vector] for vector in (r, v))
    driver_text = f"\n    driver: {{angle: '{driver}'}}" if driver else ""
    return f"""
casmech: 1
name: pendulum
gravity: [0, 0, -{G}]
bodies:
  - name: bar
    mass: {M}
    inertia: [{I_CM}, {I_CM}, 0.01]
    position: {r}
    orientation: {{axis_angle: {{axis: [1, 0, 0], angle: {theta0}}}}}
    velocity: {v}
    angular_velocity: [{omega0}, 0, 0]
joints:
  - name: pivot
    type: revolute
    body_i: ground
    body_j: bar
    at: [0, 0, 0]
    axis: [1, 0, 0]{driver_text}
{extra_joint}
analysis: {{type: assembly}}
"""


def assemble(text):
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions, "assembly")
    return Table(*casmech.results_table(functions, result))


def angle_of(table):
    return np.arctan2(table["bar.y"], -table["bar.z"])[0]


@pytest.mark.parametrize("target", [0.7, 3.0, -3.0, 2.5 * np.pi, 10.0])
def test_driver_continuation_reaches_the_driven_angle_not_its_mirror(target):
    """sin(theta - f) also vanishes at theta = f + pi; continuation must not land there."""
    table = assemble(pendulum(driver=f"{target} + 0*t"))
    wrapped = (target + np.pi) % (2 * np.pi) - np.pi
    # Newton converges to |Phi| <= 1e-12
    np.testing.assert_allclose(angle_of(table), wrapped, rtol=0, atol=1e-10)


@pytest.mark.parametrize("theta0, omega0", [(0.4, 0.0), (-1.1, 2.5), (2.0, -1.0)])
def test_free_pendulum_accelerations_and_reaction_from_eom(theta0, omega0):
    """At any instant: I_O theta'' = -m g L sin(theta); the joint force on the bar is
    m (a_cm - g), a_cm with tangential L theta'' and centripetal L theta'^2 parts."""
    table = assemble(pendulum(theta0, omega0))
    i_o = I_CM + M * L**2
    alpha = -M * G * L * np.sin(theta0) / i_o
    # closed form vs a linear solve of a 14x14 system: roundoff only
    np.testing.assert_allclose(table["bar.alphax"], alpha, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(table["bar.wx"], omega0, rtol=1e-12, atol=1e-12)
    a_cm = np.array([0.0,
                     L * (np.cos(theta0) * alpha - np.sin(theta0) * omega0**2),
                     L * (np.sin(theta0) * alpha + np.cos(theta0) * omega0**2)])
    force = M * (a_cm - np.array([0, 0, -G]))
    for k, axis in enumerate("xyz"):
        np.testing.assert_allclose(table[f"bar.a{axis}"], a_cm[k], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(table[f"pivot.f{axis}"], force[k], rtol=1e-10, atol=1e-10)
    # an undriven revolute transmits no torque about its own axis
    np.testing.assert_allclose(table["pivot.tx"], 0, rtol=0, atol=1e-10)


def test_file_velocities_are_projected_onto_the_constraints():
    """A velocity along the joint axis violates the revolute; assembly removes it and keeps the
    compatible part."""
    table = assemble(pendulum(0.0, 0.0, file_velocity=[1.0, 0.5, 0.0]))
    np.testing.assert_allclose(table["bar.vx"], 0, rtol=0, atol=1e-12)  # roundoff
    assert table["bar.vy"][0] > 0.1  # the compatible swing velocity survives


def test_assembly_failure_names_the_joint():
    """A distance constraint that no pose satisfies (tip 5 m away from a point 10 m up)."""
    impossible = """  - {name: tether, type: d, body_i: ground, s_i: [0, 0, 10], body_j: bar,
     s_j: [0, 0, -0.5], f: "1"}"""
    functions = casmech.compile(casmech.loads(pendulum(extra_joint=impossible)))
    with pytest.raises(AnalysisError) as failure:
        casmech.analyze(functions, "assembly")
    message = str(failure.value)
    assert "did not converge" in message and "joint 'tether'" in message
    assert "<string>:" in message  # the joint's location in the model text


def test_progress_is_called_with_every_row_time():
    """analyze(progress=...) sees each output time once, in order, as rows are made."""
    functions = casmech.compile(casmech.load(MODELS / "me751_pendulum.yaml"))
    seen = []
    result = casmech.analyze(functions, t_end=0.05, progress=seen.append)
    assert seen == result.times
