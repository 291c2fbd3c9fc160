"""Optimal control: the optimal controls replayed through IDAS reproduce the optimal trajectory,
satisfy the bounds and terminal conditions, and both transcriptions reach the same optimum."""


import numpy as np
import pytest

import casmech
from casmech.errors import UsageError
from casmech.optimal.controls import Control
from casmech.optimal.ocp import OCP, columns_at, from_block, replay, solve
from tests.conftest import MODELS

MODEL = MODELS / "ocp_pendulum_swing_up.yaml"
ANGLE = 1.2  # target swing angle [rad]: e0 = cos(angle / 2) at rest


def test_collocation_and_shooting_reach_the_same_replayable_optimum():
    model = casmech.load(MODEL)
    problem = OCP([Control("pivot", "torque", -6.0, 6.0)], horizon=1.0, intervals=6,
                  terminal={"bar.e0": np.cos(ANGLE / 2), "bar.wx": 0.0}, rtol=1e-9, atol=1e-11)
    collocation = solve(model, problem, "collocation")
    shooting = solve(model, problem, "shooting", start=collocation)
    for solution in (collocation, shooting):
        replayed = replay(model, problem, solution)
        n = replayed.shape[1] // 2
        # the bound on positions; measured 2.0e-5 (collocation, Radau 3, h = 1/6 s) and
        # 5e-11 (shooting: the same IDAS)
        np.testing.assert_allclose(replayed[:, :n], solution.x[:, :n], rtol=0, atol=1e-4)
        assert np.all(np.abs(solution.u) <= 6.0 + 1e-8)  # bounds (IPOPT's tolerance)
        end = columns_at(model, problem, solution, ["bar.e0", "bar.wx"])[-1]
        # terminal equalities hold to IPOPT's constraint tolerance
        np.testing.assert_allclose(end, [np.cos(ANGLE / 2), 0.0], rtol=0, atol=1e-7)
    # the bound; measured 1.7e-5 relative (collocation's discretisation error)
    np.testing.assert_allclose(shooting.objective, collocation.objective, rtol=1e-3, atol=0)


def test_controls_need_a_matching_joint():
    model = casmech.load(MODEL)
    with pytest.raises(UsageError, match="needs a joint of type translational"):
        solve(model, OCP([Control("pivot", "force")], horizon=1.0, intervals=2))


SLIDER = """
casmech: 1
name: slider
bodies:
  - {name: cart, mass: 1.0, inertia: [0.1, 0.1, 0.1], position: [0, 0, 0]}
joints:
  - {name: track, type: translational, body_i: ground, body_j: cart, at: [0, 0, 0],
     axis: [0, 1, 0]}
"""


def test_minimum_time_rest_to_rest_matches_the_bang_bang_closed_form():
    """Rest to rest over D = 1 m with |F| <= 2 N on m = 1 kg: T* = 2 sqrt(D m / F) (accelerate
    for half the time, brake for the other half; exact with an even number of intervals)."""
    model = casmech.loads(SLIDER)
    problem = OCP([Control("track", "force", -2.0, 2.0)], horizon=2.0, intervals=4, effort=0.0,
                  terminal={"cart.y": 1.0, "cart.vy": 0.0}, free_time=(0.5, 5.0),
                  time_weight=1.0)
    collocation = solve(model, problem, "collocation")
    shooting = solve(model, problem, "shooting", start=collocation)
    for solution in (collocation, shooting):
        # bang-bang is exact on this grid: T to IPOPT's tolerance (measured ~1e-9)
        np.testing.assert_allclose(solution.times[-1], 2 * np.sqrt(0.5), rtol=1e-6, atol=0)
        np.testing.assert_allclose(solution.u.ravel(), [2, 2, -2, -2], rtol=0, atol=1e-5)
        replayed = replay(model, problem, solution)
        # a polynomial motion: collocation and IDAS both reproduce it (measured ~1e-10)
        np.testing.assert_allclose(replayed[:, :7], solution.x[:, :7], rtol=0, atol=1e-6)


def test_bound_on_a_reaction_force_is_active_and_respected():
    """Limit the pivot's force along z below what the free optimum needs: the bound holds at
    every node and the optimum costs more."""
    model = casmech.load(MODEL)
    free = OCP([Control("pivot", "torque", -6.0, 6.0)], horizon=1.0, intervals=10,
               terminal={"bar.e0": np.cos(ANGLE / 2), "bar.wx": 0.0})
    loose = solve(model, free, "collocation")
    peak = columns_at(model, free, loose, ["pivot.fz"])[1:, 0].max()
    limit = 0.97 * peak
    bounded = OCP(free.controls, free.horizon, free.intervals, terminal=free.terminal,
                  path={"pivot.fz": (-100.0, limit)})
    tight = solve(model, bounded, "collocation")
    force = columns_at(model, bounded, tight, ["pivot.fz"])[1:, 0]
    assert force.max() <= limit + 1e-6  # IPOPT's constraint tolerance, in newtons
    assert force.max() >= limit - 1e-3  # the bound is active
    assert tight.objective > loose.objective
@pytest.mark.slow  # long validation: `python -m pytest -m slow` runs it
def test_compiled_and_interpreted_collocation_reach_the_same_optimum():
    """The cart-pole swing-up on the C functions of casmech.compile(model, "compiled")
    and on the interpreted SX graphs: two NLPs, one optimum."""
    from casmech.backends import codegen
    if not codegen.available():
        pytest.skip("no C compiler")
    model = casmech.load(MODEL.with_name("ocp_cart_pole_swing_up.yaml"))
    problem, _ = from_block(model.ocp)
    problem = OCP(**{**problem.__dict__, "intervals": 8, "formulation": "bodies"})
    # the same IPOPT algorithm on both (limited-memory Hessian: all the externals provide),
    # from the same start (the exact-Hessian KKT point, objective 122.9: from there both
    # descend to 86.95; from the forward-simulation guess the two runs part ways)
    start = solve(model, problem, "collocation")
    settings = {"ipopt.hessian_approximation": "limited-memory"}
    interpreted = solve(model, problem, "collocation", max_iter=1000, options=settings,
                        start=start)
    compiled = solve(model, OCP(**{**problem.__dict__, "mode": "compiled"}), "collocation",
                     max_iter=1000, start=start)
    assert compiled.objective < start.objective
    # the brief's bound; measured 3e-15 relative (both solved to IPOPT's tol 1e-10)
    np.testing.assert_allclose(compiled.objective, interpreted.objective, rtol=1e-6, atol=0)
    np.testing.assert_allclose(compiled.u, interpreted.u, rtol=0, atol=1e-4)  # newtons


FLAT_PENDULUM = """
casmech: 1
name: flat_pendulum
parameters: {L: 1.0, m: 1.0}
gravity: [0, 0, -9.81]
bodies:
  - {name: arm_bar, mass: m, inertia: [m * L**2 / 12, m * L**2 / 12, 1.0e-4],
     position: [0, 0, -L/2]}
joints:
  - {name: arm_pivot, type: revolute, body_i: ground, body_j: arm_bar, at: [0, 0, 0],
     axis: [1, 0, 0]}
"""
COMPOSED_PENDULUM = """
casmech: 1
name: composed_pendulum
parameters: {L: 1.0, m: 1.0}
gravity: [0, 0, -9.81]
components:
  rod:
    parameters: {L: 1.0, m: 1.0}
    bodies:
      - {name: bar, mass: m, inertia: [m * L**2 / 12, m * L**2 / 12, 1.0e-4],
         position: [0, 0, -L/2]}
    joints:
      - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0],
         axis: [1, 0, 0]}
instances:
  - {name: arm, component: rod, parameters: {L: L, m: m}}
"""


def test_a_composed_model_solves_as_the_same_model_written_flat():
    """Optimal control re-reads no parameter expression, so a composed model (an instance of
    a component) runs, and reaches the optimum of the same pendulum written out flat (on
    body coordinates: a control on a component's joint is not one the joint formulation
    takes, optimal/joint_model.py)."""
    def problem(arm: str) -> OCP:  # the flat model's names: arm_bar, arm_pivot
        return OCP([Control(f"arm{arm}pivot", "torque", -6.0, 6.0)], horizon=1.0, intervals=6,
                   terminal={f"arm{arm}bar.e0": np.cos(ANGLE / 2), f"arm{arm}bar.wx": 0.0},
                   rtol=1e-9, atol=1e-11, formulation="bodies")

    flat = solve(casmech.loads(FLAT_PENDULUM), problem("_"), "collocation")
    composed = solve(casmech.loads(COMPOSED_PENDULUM), problem("."), "collocation")
    # one NLP written two ways (the composed one over the model data): IPOPT's tolerance 1e-8
    np.testing.assert_allclose(composed.objective, flat.objective, rtol=1e-7, atol=0)
    np.testing.assert_allclose(composed.u, flat.u, rtol=0, atol=1e-5)
