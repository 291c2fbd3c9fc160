"""Joint states as results columns (docs/format.md, results contract): `<joint>.angle`,
`.angle_dot`, `.displacement`, `.displacement_dot`, a universal joint's `angle_i`, `angle_j`
and rates, a spherical joint's `e0..e3` and `wx..wz`, checked against closed forms of the
slider-crank (tests/helpers/linkage_closed_forms.py), a statics closed form, and across formulations
with a second computation from the body columns."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import casmech
from tests.conftest import MODELS, Table, run_model
from tests.helpers import linkage_closed_forms as closed_forms
from tests.helpers.reference_data import MOTION, columns, rotation


def wrapped(angle):
    return np.remainder(np.asarray(angle) + np.pi, 2 * np.pi) - np.pi


@pytest.mark.parametrize("analysis", ["kinematics", "inverse_dynamics"])
def test_slider_crank_joint_columns_are_the_closed_forms(analysis):
    """Crank angle w t, the slider's travel, the rod's rotation relative to the crank (a
    spherical joint's Euler parameters and relative angular velocity) and relative to the
    slider (a universal joint's angle about z), all from the loop closure."""
    _, table = run_model(MODELS / "slider_crank.yaml", analysis=analysis, t_end=2.0,
                         output_step=0.01)
    t = table["t"]
    exact = closed_forms.slider_crank(0.5, 2.0, 2 * np.pi)
    crank, crank_rate, _ = exact["crank.angle"](t)
    rod, rod_rate, _ = exact["rod.angle"](t)
    slider, slider_rate, _ = exact["slider.x"](t)
    atol = 1e-9  # positions assembled to 1e-12, rates solved to round-off of a 2 pi speed
    np.testing.assert_allclose(wrapped(table["crank_pivot.angle"] - crank), 0, rtol=0, atol=atol)
    np.testing.assert_allclose(table["crank_pivot.angle_dot"], crank_rate, rtol=0, atol=atol)
    np.testing.assert_allclose(table["slide.displacement"], slider - 2.5, rtol=0, atol=atol)
    np.testing.assert_allclose(table["slide.displacement_dot"], slider_rate, rtol=0, atol=atol)
    relative = rod - crank  # the rod turned against the crank, continuous in t
    np.testing.assert_allclose(table["crank_pin.e0"], np.cos(relative / 2), rtol=0, atol=atol)
    np.testing.assert_allclose(table["crank_pin.e3"], np.sin(relative / 2), rtol=0, atol=atol)
    for k in (1, 2):
        np.testing.assert_allclose(table[f"crank_pin.e{k}"], 0, rtol=0, atol=atol)
    np.testing.assert_allclose(table["crank_pin.wz"], rod_rate - crank_rate, rtol=0, atol=atol)
    np.testing.assert_allclose(table["wrist_pin.angle_i"], wrapped(rod), rtol=0, atol=atol)
    np.testing.assert_allclose(table["wrist_pin.angle_i_dot"], rod_rate, rtol=0, atol=atol)
    np.testing.assert_allclose(table["wrist_pin.angle_j"], 0, rtol=0, atol=atol)


def body_angle(table, body: str) -> np.ndarray:
    """A body's rotation about y since t = 0, from its Euler parameter columns (numpy)."""
    a = rotation(columns(table, body, MOTION["Quat"]))
    relative = a @ a[0].T
    return np.arctan2(relative[:, 0, 2], relative[:, 0, 0])


def test_double_pendulum_angles_agree_across_formulations_and_with_the_bodies():
    """pivot.angle is rod1's rotation about the hinge axis y; elbow.angle rod2's less rod1's;
    rp, romega and joint coordinates give the same columns."""
    tables = {}
    for formulation in ("rp", "romega", "joint"):
        _, tables[formulation] = run_model(MODELS / "double_pendulum.yaml", analysis="dynamics",
                                           formulation=formulation, t_end=1.0)
    table = tables["rp"]
    # the same rotation by two formulas (atol: the run's constraint residuals, < 1e-9)
    np.testing.assert_allclose(wrapped(table["pivot.angle"] - body_angle(table, "rod1")), 0,
                               rtol=0, atol=1e-9)
    elbow = body_angle(table, "rod2") - body_angle(table, "rod1")
    np.testing.assert_allclose(wrapped(table["elbow.angle"] - elbow), 0, rtol=0, atol=1e-9)
    # angular velocities add about y (atol: the velocity constraints' residuals in the run)
    np.testing.assert_allclose(table["pivot.angle_dot"], table["rod1.wy"], rtol=0, atol=1e-8)
    np.testing.assert_allclose(table["elbow.angle_dot"], table["rod2.wy"] - table["rod1.wy"],
                               rtol=0, atol=1e-8)
    for other in ("romega", "joint"):
        for column in ("pivot.angle", "pivot.angle_dot", "elbow.angle", "elbow.angle_dot"):
            np.testing.assert_allclose(tables[other][column], table[column], rtol=1e-6,
                                       atol=1e-6)  # each integrated to the model's rtol 1e-8


SPRING_PENDULUM = """\
casmech: 1
name: spring_pendulum
parameters: {m: 2.0, L: 1.0, k: 30.0}
gravity: [0, 0, -9.81]
bodies:
  - {name: bar, mass: m, inertia: [0.2, 0.2, 0.01], position: [L/2, 0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, -1, 0]}
forces:
  - {name: spring, type: rsda, joint: pivot, stiffness: k}
analysis: {type: statics}
"""


def test_statics_reports_the_equilibrium_angle():
    """A horizontal bar on a torsion spring sags until k theta = m g (L/2) cos(theta); a
    positive angle about the axis -y lifts the bar, so the column reads -theta."""
    functions = casmech.compile(casmech.loads(SPRING_PENDULUM))
    table = Table(*casmech.results_table(functions, casmech.analyze(functions)))
    theta = brentq(lambda a: 30.0 * a - 2.0 * 9.81 * 0.5 * math.cos(a), 0, math.pi / 2)
    np.testing.assert_allclose(table["pivot.angle"][0], -theta, rtol=0,
                               atol=1e-9)  # statics converges to 1e-10 of the loads
    assert table["pivot.angle_dot"][0] == 0.0
