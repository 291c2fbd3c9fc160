"""Optimal control: the optimal controls replayed through IDAS reproduce the optimal trajectory,
satisfy the bounds and terminal conditions, and both transcriptions reach the same optimum."""

from pathlib import Path

import numpy as np
import pytest

import casmech
from casmech.errors import UsageError
from casmech.optimal.controls import Control
from casmech.optimal.ocp import OCP, columns_at, replay, solve

MODEL = Path(__file__).parents[2] / "models" / "ocp_pendulum_swing_up.yaml"
ANGLE = 1.2  # target swing angle [rad]: e0 = cos(angle / 2) at rest


def test_collocation_and_shooting_reach_the_same_replayable_optimum():
    model = casmech.load(MODEL)
    problem = OCP([Control("pivot", "torque", -6.0, 6.0)], horizon=1.0, intervals=10,
                  terminal={"bar.e0": np.cos(ANGLE / 2), "bar.wx": 0.0}, rtol=1e-9, atol=1e-11)
    collocation = solve(model, problem, "collocation")
    shooting = solve(model, problem, "shooting", start=collocation)
    for solution in (collocation, shooting):
        replayed = replay(model, problem, solution)
        n = replayed.shape[1] // 2
        # the bound on positions; measured 3e-5 (collocation, Radau 3, h = 0.1 s) and
        # 1e-9 (shooting: the same IDAS)
        np.testing.assert_allclose(replayed[:, :n], solution.x[:, :n], rtol=0, atol=1e-4)
        assert np.all(np.abs(solution.u) <= 6.0 + 1e-8)  # bounds (IPOPT's tolerance)
        end = columns_at(model, problem, solution, ["bar.e0", "bar.wx"])[-1]
        # terminal equalities hold to IPOPT's constraint tolerance
        np.testing.assert_allclose(end, [np.cos(ANGLE / 2), 0.0], rtol=0, atol=1e-7)
    # the bound; measured ~1e-5 relative (collocation's discretisation error)
    np.testing.assert_allclose(shooting.objective, collocation.objective, rtol=1e-3, atol=0)


def test_controls_need_a_matching_joint():
    model = casmech.load(MODEL)
    with pytest.raises(UsageError, match="needs a joint of type translational"):
        solve(model, OCP([Control("pivot", "force")], horizon=1.0, intervals=2))
