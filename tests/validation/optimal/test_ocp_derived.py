"""A cost term that reads a parameter derived from a decision parameter follows it
(optimal/joint_model.py's derived, optimal/costs.py): the disk's inertia J = 2 R^2 with its
radius R among the unknowns, and a Mayer term on J."""

import numpy as np

import casmech
from casmech.optimal.controls import Control
from casmech.optimal.ocp import OCP, solve

DISK = """
casmech: 1
name: disk
parameters: {R: 0.5, J: 2 * R**2}
bodies:
  - {name: disk, mass: 2.0, inertia: [0.3, 0.3, J], position: [0, 0, 0]}
joints:
  - {name: spin, type: revolute, body_i: ground, body_j: disk, at: [0, 0, 0], axis: [0, 0, 1]}
"""


def test_a_mayer_term_on_a_derived_parameter_follows_the_decision_parameter():
    """Rest to rest through PHI = 1 in T = 2: the least effort is 12 J^2 PHI^2 / T^3 =
    1.5 J^2 (piecewise-linear torques hold it exactly), plus the Mayer term (J - 0.5)^2:
    the sum is least at J = 0.2, R = sqrt(0.1), cost 0.15. Were J the file's number (0.5)
    in the Mayer term, it would be constant and the optimum R its lower bound."""
    problem = OCP([Control("spin", "torque")], horizon=2.0, intervals=8,
                  terminal={"spin.angle": 1.0, "spin.angle_dot": 0.0}, piecewise="linear",
                  parameters={"R": (0.1, 1.0)}, final="(J - 0.5)**2")
    solution = solve(casmech.loads(DISK), problem, "collocation")
    # the closed form, to IPOPT's tolerance (tol 1e-10) through the square root
    np.testing.assert_allclose(solution.design, [np.sqrt(0.1)], rtol=1e-7, atol=0)
    np.testing.assert_allclose(solution.objective, 0.15, rtol=1e-8, atol=0)  # as above
