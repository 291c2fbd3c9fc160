"""Forward dynamics (IDAS) against closed forms."""

import numpy as np

import casmech
from casmech.runtime.dynamics import DRIFT_TOLERANCE
from tests.conftest import Table

G = np.array([0.0, 0.0, -9.81])
W = 3.0  # spin about the body z axis, a principal axis [rad/s]

FREE_BODY = f"""
casmech: 1
name: thrown_spinning_box
bodies:
  - name: box
    mass: 2.0
    inertia: [0.3, 0.4, 0.5]
    position: [0, 0, 1]
    velocity: [1.0, -0.5, 4.0]
    angular_velocity: [0, 0, {W}]
analysis: {{type: dynamics, t_end: 2, output_step: 0.01, rtol: 1.0e-10, atol: 1.0e-12}}
"""

PENDULUM = """
casmech: 1
name: pendulum
bodies:
  - {name: bar, mass: 1.0, inertia: [0.1, 0.1, 0.01], position: [0, 1, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [1, 0, 0]}
analysis: {type: dynamics, t_end: 3, output_step: 0.01}
"""


def simulate(text, **kwargs):
    functions = casmech.compile(casmech.loads(text))
    return Table(*casmech.results_table(functions, casmech.analyze(functions, **kwargs)))


def test_free_flight_with_spin_about_a_principal_axis():
    """No constraints: a parabola for the CM and steady rotation e = (cos(wt/2), 0, 0,
    sin(wt/2)) (torque-free spin about a principal axis is steady)."""
    table = simulate(FREE_BODY)
    t = table["t"]
    start, velocity = np.array([0, 0, 1.0]), np.array([1.0, -0.5, 4.0])
    position = start[:, None] + np.outer(velocity, t) + 0.5 * np.outer(G, t**2)
    for k, axis in enumerate("xyz"):
        # rtol 1e-10 on O(1) states over 2 s: BDF global error measured ~1e-9
        np.testing.assert_allclose(table[f"box.{axis}"], position[k], rtol=0, atol=1e-8)
        np.testing.assert_allclose(table[f"box.a{axis}"], G[k], rtol=0, atol=1e-10)
    np.testing.assert_allclose(table["box.e0"], np.cos(W * t / 2), rtol=0, atol=1e-8)
    np.testing.assert_allclose(table["box.e3"], np.sin(W * t / 2), rtol=0, atol=1e-8)
    np.testing.assert_allclose(table["box.wz"], W, rtol=0, atol=1e-8)
    # conservative: kinetic + potential constant (relative 1e-9 at rtol 1e-10)
    np.testing.assert_allclose(table["energy"], table["energy"][0], rtol=1e-9, atol=0)


def test_pendulum_keeps_constraints_and_energy_and_converges_with_rtol():
    loose = simulate(PENDULUM.replace("output_step: 0.01", "output_step: 0.01, rtol: 1.0e-7, "
                                                           "atol: 1.0e-9"))
    tight = simulate(PENDULUM.replace("output_step: 0.01", "output_step: 0.01, rtol: 1.0e-11, "
                                                           "atol: 1.0e-13"))
    reference = simulate(PENDULUM.replace("output_step: 0.01", "output_step: 0.01, "
                                          "rtol: 1.0e-13, atol: 1.0e-15"))
    for table in (loose, tight):
        assert np.max(table["constraint_violation"]) <= DRIFT_TOLERANCE
    error = {name: np.max(np.abs(table["bar.y"] - reference["bar.y"]))
             for name, table in (("loose", loose), ("tight", tight))}
    assert error["tight"] <= error["loose"] / 100  # 10^4 tighter rtol: at least 100x smaller
    # energy of a conservative model at rtol 1e-11: constant to 1e-8 of its scale m g L
    # (the energy itself starts at 0: the bar is released level with the pivot)
    assert np.ptp(tight["energy"]) <= 1e-8 * 1.0 * 9.81 * 1.0
