"""Terminal and path conditions on an angle column read the joint's continuous angle
(optimal/costs.py continued), not the results table's value wrapped into (-pi, pi]: a
pendulum swung up to pi, to -pi (the other way round) and to 3 pi (one more turn) ends
there, as the results table's angles, unwrapped from node to node, and the bar's height
(upright: z = L/2) say."""

from dataclasses import replace

import numpy as np
import pytest

import casmech
from casmech.optimal.ocp import columns_at, from_block, solve
from tests.conftest import MODELS


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))


def _swing(target: float, **settings):
    model = casmech.load(MODELS / "ocp_pendulum_swing_up.yaml")
    problem = replace(from_block(model.ocp)[0],
                      terminal={"pivot.angle": target, "pivot.angle_dot": 0.0}, **settings)
    solution = solve(model, problem, "collocation")
    columns = columns_at(model, problem, solution, ["pivot.angle", "bar.z"])
    # the table's angles unwrapped: the nodes are far less than pi apart in angle
    return solution, np.unwrap(columns[:, 0]), columns[:, 1]


@pytest.mark.parametrize("target, settings", [
    (np.pi, {}), (-np.pi, {}),
    (3 * np.pi, {"horizon": 3.0, "intervals": 30, "guess": [4.0]})],
    ids=["pi", "minus-pi", "three-pi"])
def test_a_terminal_angle_past_pi_is_reached(target, settings):
    solution, angle, height = _swing(target, **settings)
    assert solution.status == "Solve_Succeeded"
    # an equality constraint of the NLP, met to IPOPT's tolerance (1e-10)
    np.testing.assert_allclose(angle[-1], target, rtol=0, atol=1e-8)
    # upright: the bar's centre L/2 = 0.5 m above the pivot, a body column
    np.testing.assert_allclose(height[-1], 0.5, rtol=0, atol=1e-8)


def test_pi_and_minus_pi_are_mirror_optima():
    """The pendulum is symmetric: swinging up either way costs the same."""
    up, _, _ = _swing(np.pi)
    down, _, _ = _swing(-np.pi)
    # two solves of mirror NLPs from mirror-free guesses: IPOPT's tolerance (1e-10)
    np.testing.assert_allclose(up.objective, down.objective, rtol=1e-8, atol=0)


def test_a_path_bound_on_the_continuous_angle_holds_across_pi():
    """One more turn (to 3 pi) with the angle in [-0.2, 3 pi + 0.1] along the way: the free
    optimum's continued angle rises from 0 to 3 pi inside that range, so the bound is
    inactive and the optimum the same; read wrapped, every pass over the top would jump to
    -pi and the bound would forbid the turn."""
    settings = {"horizon": 3.0, "intervals": 30, "guess": [4.0]}
    free, free_angle, _ = _swing(3 * np.pi, **settings)
    bounded, angle, height = _swing(3 * np.pi, path={"pivot.angle": (-0.2, 3 * np.pi + 0.1)},
                                    **settings)
    assert free_angle.min() >= -0.2 and free_angle.max() <= 3 * np.pi + 0.1
    assert bounded.status == "Solve_Succeeded"
    # the same NLP optimum with an inactive bound: IPOPT's tolerance (1e-10)
    np.testing.assert_allclose(bounded.objective, free.objective, rtol=1e-8, atol=0)
    np.testing.assert_allclose(angle[-1], 3 * np.pi, rtol=0, atol=1e-8)  # as above
    np.testing.assert_allclose(height[-1], 0.5, rtol=0, atol=1e-8)  # as above
