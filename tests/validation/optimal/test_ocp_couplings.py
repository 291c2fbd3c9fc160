"""Optimal control through a gear: a rest-to-rest turn of the driven disk by a torque on the
driving one, minimum effort, against the discrete optimum computed here by least norm."""

import numpy as np

import casmech
from casmech.optimal.controls import Control
from casmech.optimal.ocp import OCP, columns_at, solve

J1, J2, RATIO, TARGET, HORIZON, N = 0.5, 0.7, -2.5, 1.0, 1.0, 10
TEXT = f"""
casmech: 1
name: gear_ocp
bodies:
  - {{name: d1, mass: 2.0, inertia: [0.3, 0.3, {J1}], position: [0, 0, 0]}}
  - {{name: d2, mass: 3.0, inertia: [0.4, 0.4, {J2}], position: [1, 0, 0]}}
joints:
  - {{name: p1, type: revolute, body_i: ground, body_j: d1, at: [0, 0, 0], axis: [0, 0, 1]}}
  - {{name: p2, type: revolute, body_i: ground, body_j: d2, at: [1, 0, 0], axis: [0, 0, 1]}}
  - {{name: mesh, type: gear, joint_i: p1, joint_j: p2, ratio: {RATIO}}}
"""


def least_effort() -> float:
    """min h sum u_k^2 over torques u_k held on N equal intervals that turn an inertia
    J1 + r^2 J2 from rest to rest by TARGET / r: the least-norm solution of the two linear
    conditions (final angle, final rate)."""
    inertia, h = J1 + RATIO ** 2 * J2, HORIZON / N
    ends = h * np.arange(1, N + 1)
    conditions = np.array([h * (HORIZON - ends) + h ** 2 / 2, np.full(N, h)]) / inertia
    u = np.linalg.lstsq(conditions, [TARGET / RATIO, 0.0], rcond=None)[0]
    return h * u @ u


def test_a_rest_to_rest_turn_through_a_gear_costs_the_discrete_optimum():
    model = casmech.loads(TEXT)
    problem = OCP([Control("p1", "torque", -100.0, 100.0)], horizon=HORIZON, intervals=N,
                  terminal={"p2.angle": TARGET, "p2.angle_dot": 0.0}, rtol=1e-9, atol=1e-11)
    solution = solve(model, problem, "collocation")
    # collocation is exact for piecewise constant torques (quadratic angles): IPOPT's tolerance
    np.testing.assert_allclose(solution.objective, least_effort(), rtol=1e-7, atol=0)
    end = columns_at(model, problem, solution, ["p1.angle", "p2.angle"])[-1]
    # the gear holds at the end: the terminal condition and the coupling, to IPOPT's tolerance
    np.testing.assert_allclose(end, [TARGET / RATIO, TARGET], rtol=0, atol=1e-7)
