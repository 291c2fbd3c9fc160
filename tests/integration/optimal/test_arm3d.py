"""Minimum-effort point-to-point move of a 3D arm (models/ocp_arm3d.yaml, issue 7 item 4):
stabilised Radau collocation from the interpolated rest-to-rest guess, replayed through IDAS."""


import numpy as np
import pytest

import casmech
from casmech.optimal.ocp import OCP, columns_at, from_block, replay, solve
from tests.conftest import MODELS

MODEL = MODELS / "ocp_arm3d.yaml"
TIP = ["payload.x", "payload.y", "payload.z"]


def _problem(model) -> OCP:
    problem, _ = from_block(model.ocp)
    assert problem.stabilized and problem.initial_guess == "interpolation"  # from the block
    # a coarser control grid than the example's 12 x 3, 6 collocation elements per interval
    return OCP(**{**problem.__dict__, "intervals": 6, "elements": 6, "rtol": 1e-9,
                  "atol": 1e-11})
@pytest.mark.slow  # long validation: `python -m pytest -m slow` runs it
def test_arm_reaches_the_target_at_rest_and_replays():
    model = casmech.load(MODEL)
    problem = _problem(model)
    solution = solve(model, problem, "collocation")
    assert solution.status == "Solve_Succeeded"
    n = solution.x.shape[1] // 2
    replayed = replay(model, problem, solution)
    # the bound on positions; measured 4.9e-5 (6 intervals x 6 elements)
    np.testing.assert_allclose(replayed[:, :n], solution.x[:, :n], rtol=0, atol=1e-4)
    bounds = np.array([[c.lower, c.upper] for c in problem.controls])
    assert np.all(solution.u >= bounds[:, 0] - 1e-8)  # IPOPT's bound tolerance
    assert np.all(solution.u <= bounds[:, 1] + 1e-8)
    target = [model.ocp.terminal[c] for c in TIP]
    # the IDAS replay ends at the target (measured 4.9e-5 off) and at rest
    end = replayed[-1]
    tip = end[[solution_index(model, c) for c in TIP]]
    np.testing.assert_allclose(tip, target, rtol=0, atol=1e-4)
    np.testing.assert_allclose(end[n:], 0.0, rtol=0, atol=1e-3)  # measured 1.7e-4 (rates)
    # the tip is the forearm's end point: r_forearm + A(p_forearm) [L2/2, 0, 0] (independent
    # of the weld rows that carry the payload; closed form of the Euler-parameter matrix)
    forearm = columns_at(model, problem, solution, ["forearm.x", "forearm.y", "forearm.z",
                                                    "forearm.e0", "forearm.e1", "forearm.e2",
                                                    "forearm.e3"])[-1]
    r, (e0, e1, e2, e3) = forearm[:3], forearm[3:]
    x_axis = np.array([e0**2 + e1**2 - e2**2 - e3**2, 2 * (e1 * e2 + e0 * e3),
                       2 * (e1 * e3 - e0 * e2)])
    # terminal equality at IPOPT's tolerance, position constraints exact at the nodes
    np.testing.assert_allclose(r + model.parameters["L2"] / 2 * x_axis, target, rtol=0,
                               atol=1e-8)


def solution_index(model, column: str) -> int:
    """Index of a CM coordinate column in the state x = [r_1..r_nb, p_1..p_nb, ...]."""
    body, _, axis = column.partition(".")
    names = [b.name for b in model.bodies]
    return 3 * names.index(body) + "xyz".index(axis)
