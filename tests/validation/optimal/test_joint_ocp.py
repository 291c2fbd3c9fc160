"""Optimal control in joint coordinates (optimal/joint_model.py, joint_ocp.py): the dynamics
against Lagrange's equations written by hand, a closed-form optimum, the same optimum as a
rockit script of the same problem, and every gallery OCP replayed by DOP853 from its nodes."""

import importlib.util

import numpy as np
import pytest

import casmech
from casmech.errors import UsageError
from casmech.optimal.controls import Control
from casmech.optimal.ocp import (
    OCP,
    columns_at,
    fine_columns,
    from_block,
    joints_of,
    replay,
    solve,
)
from tests.conftest import ROOT

MODELS = ROOT / "models"
GALLERY = sorted(MODELS.glob("ocp_*.yaml"))


def hand_written():
    """benchmarks/rockit_ocp.py: the cart-pole's and double pendulum's equations by hand."""
    spec = importlib.util.spec_from_file_location("rockit_ocp", ROOT / "benchmarks" /
                                                  "rockit_ocp.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("name, rates", [("ocp_cart_pole_swing_up", "cart_pole_rates"),
                                         ("ocp_double_pendulum_swing_up",
                                          "double_pendulum_rates")])
def test_joint_ode_is_lagranges(name, rates):
    """The ODE in joint coordinates with the controls as effort motors equals the equations
    of motion derived by hand, at scattered states and controls."""
    model = casmech.load(MODELS / f"{name}.yaml")
    problem, _ = from_block(model.ocp)
    joints = joints_of(model, problem)
    by_hand = getattr(hand_written(), rates)
    generator = np.random.default_rng(3)
    for _ in range(5):
        x, u = generator.normal(size=4) * 2, generator.normal(size=joints.n_u) * 5
        got = np.array(joints.rhs(0.0, x, u).full()).ravel()
        expected = np.array(by_hand(x, u if u.size > 1 else u[0])).astype(float).ravel()
        # two exact formulations of one ODE: round-off of the articulated-body recursion
        np.testing.assert_allclose(got, expected, rtol=1e-10, atol=1e-10)


DISK = """
casmech: 1
name: disk
parameters: {J: 0.5}
bodies:
  - {name: disk, mass: 2.0, inertia: [0.3, 0.3, J], position: [0, 0, 0]}
joints:
  - {name: spin, type: revolute, body_i: ground, body_j: disk, at: [0, 0, 0], axis: [0, 0, 1]}
"""


@pytest.mark.parametrize("transcription", ["collocation", "shooting"])
def test_minimum_energy_rotation_of_a_disk_is_the_closed_form(transcription):
    """Rest to rest through PHI in T with the least int tau^2 on J theta'' = tau: tau(t) =
    6 J PHI / T^2 (1 - 2 t / T), cost 12 J^2 PHI^2 / T^3; linear in t, so piecewise-linear
    controls hold it exactly, and Radau collocation (a cubic angle) and RK4 (exact on a cubic
    too) integrate it exactly."""
    j, phi, horizon = 0.5, 1.0, 2.0
    problem = OCP([Control("spin", "torque")], horizon=horizon, intervals=8,
                  terminal={"spin.angle": phi, "spin.angle_dot": 0.0}, piecewise="linear",
                  formulation="joints")
    solution = solve(casmech.loads(DISK), problem, transcription)
    assert solution.formulation == "joints"
    torque = 6 * j * phi / horizon ** 2 * (1 - 2 * solution.times / horizon)
    # the closed form, to IPOPT's tolerance (tol 1e-10)
    np.testing.assert_allclose(solution.u[:, 0], torque, rtol=0, atol=1e-6)
    np.testing.assert_allclose(solution.objective, 12 * j ** 2 * phi ** 2 / horizon ** 3,
                               rtol=1e-6, atol=0)


def _rockit_problem(name, intervals, function):
    pytest.importorskip("rockit")
    model = casmech.load(MODELS / f"{name}.yaml")
    problem, transcription = from_block(model.ocp)
    assert problem.intervals == intervals and transcription == "collocation"
    # rockit's DirectCollocation(N, degree 3, radau): one element per interval
    problem = OCP(**{**problem.__dict__, "elements": 1, "degree": 3, "scheme": "radau"})
    ours = solve(model, problem, "collocation")
    cost, _, _ = getattr(hand_written(), function)(intervals)
    return model, problem, ours, cost


@pytest.mark.parametrize("name, intervals, function", [
    ("ocp_cart_pole_swing_up", 25, "cart_pole"),
    ("ocp_double_pendulum_swing_up", 20, "double_pendulum")])
def test_the_same_optimum_as_a_rockit_script(name, intervals, function):
    """The gallery problem against rockit with the dynamics written by hand, the same N,
    method and initial guess (benchmarks/rockit_ocp.py): one NLP, one optimum."""
    model, problem, ours, cost = _rockit_problem(name, intervals, function)
    assert ours.formulation == "joints" and ours.status == "Solve_Succeeded"
    # the bound (measured 1e-10: both at IPOPT's tol 1e-10)
    np.testing.assert_allclose(ours.objective, cost, rtol=1e-5, atol=0)


def _replayed_misses(model, problem, solution):
    replayed = replay(model, problem, solution)
    return np.max(np.abs(replayed - solution.x), axis=1)


@pytest.mark.slow
@pytest.mark.parametrize("path", GALLERY, ids=[p.stem for p in GALLERY])
def test_every_gallery_ocp_is_physical(path):
    """Each gallery OCP with its own settings: replayed by an independent integrator, the
    optimal controls take every node to the next within the tolerance, and the bodies'
    poses satisfy the joints' constraints."""
    model = casmech.load(path)
    problem, transcription = from_block(model.ocp)
    solution = solve(model, problem, transcription)
    assert solution.status == "Solve_Succeeded"
    misses = _replayed_misses(model, problem, solution)
    if solution.formulation == "joints":  # DOP853 (rtol 1e-12) from every node
        # the gallery's transcriptions' local errors (rad, m, rad/s, m/s): measured 1.3e-5
        # (pendulum), 6.3e-5 (cart-pole), 2.5e-5 (double pendulum, 6 elements)
        assert misses.max() <= 1e-3
    else:  # body coordinates (ocp_arm3d: stabilized), IDAS from the initial state
        # measured 3.5e-4 over positions and velocities (positions: 8.1e-5 m, docs/optimal.md)
        assert misses.max() <= 1e-3
    violation = columns_at(model, problem, solution, ["constraint_violation"])[:, 0]
    # joint coordinates: the tree's joints hold by construction, loop rows at every node to
    # IPOPT's tolerance; body coordinates stabilized: Phi = 0 at the points
    assert violation.max() <= 1e-8


def _four_bar():
    """The gallery four-bar with its crank free (no driver) and a torque on it, moved rest to
    rest by 0.5 rad in 1 s (away from its singular poses)."""
    text = (MODELS / "four_bar.yaml").read_text().replace(
        "    driver:\n      angle: omega * t\n", "")
    problem = OCP([Control("crank_pivot", "torque", -50, 50)], horizon=1.0, intervals=5,
                  terminal={"crank_pivot.angle": 0.5, "crank_pivot.angle_dot": 0.0},
                  guess=[0.5])
    return casmech.loads(text), problem


def test_loops_stay_on_body_coordinates_by_default():
    model, problem = _four_bar()
    assert joints_of(model, problem) is None
    assert joints_of(model, OCP(**{**problem.__dict__, "formulation": "joints"})) is not None


@pytest.mark.slow
def test_loops_in_joint_coordinates_reach_the_body_coordinates_optimum():
    """formulation: joints on a four-bar (a spherical and a universal joint: one loop, the
    tree's quaternion among the coordinates): the closure rows hold at every node, the
    replay from each node meets the next, and the optimum is the stabilized body-coordinate
    transcription's."""
    model, problem = _four_bar()
    joints = solve(model, OCP(**{**problem.__dict__, "formulation": "joints"}), "collocation")
    bodies = solve(model, OCP(**{**problem.__dict__, "formulation": "bodies",
                                 "stabilized": True}), "collocation")
    assert joints.formulation == "joints" and bodies.formulation == "bodies"
    # two transcriptions of one continuous problem (N = 5, Radau 3): measured 4e-7 relative
    np.testing.assert_allclose(joints.objective, bodies.objective, rtol=1e-5, atol=0)
    problem = OCP(**{**problem.__dict__, "formulation": "joints"})
    misses = _replayed_misses(model, problem, joints)
    assert misses.max() <= 1e-5  # measured 7e-7 (rad, rad/s)
    violation = columns_at(model, problem, joints, ["constraint_violation"])[:, 0]
    assert violation.max() <= 1e-10  # the loop's rows, imposed at every node


def test_a_reaction_bound_holds_on_the_fine_grid():
    """A bound on the pivot's force below what the free swing needs: with path_grid: fine it
    holds at every collocation point, not only at the nodes, where a bound at the nodes
    alone lets the force exceed it."""
    model = casmech.load(MODELS / "ocp_pendulum_swing_up.yaml")
    free = OCP([Control("pivot", "torque", -6.0, 6.0)], horizon=1.0, intervals=10,
               terminal={"bar.e0": np.cos(0.6), "bar.wx": 0.0})
    _, force = fine_columns(model, free, solve(model, free, "collocation"), ["pivot.fz"])
    limit = 0.97 * force.max()
    nodes = OCP(**{**free.__dict__, "path": {"pivot.fz": (-100.0, limit)}})
    fine = OCP(**{**nodes.__dict__, "path_grid": "fine"})
    _, between = fine_columns(model, nodes, solve(model, nodes, "collocation"), ["pivot.fz"])
    times, bounded = fine_columns(model, fine, solve(model, fine, "collocation"), ["pivot.fz"])
    assert len(times) == 10 * 3 + 1  # nodes and Radau points (the last point is the node)
    assert between.max() > limit + 1e-3  # the nodes' bound leaves the points between
    assert bounded.max() <= limit + 1e-6  # the bound (IPOPT's tolerance, newtons)
    assert bounded.max() >= limit - 1e-3  # the bound is active


@pytest.mark.parametrize("formulation", ["joints", "bodies"])
def test_a_control_weight_and_a_terminal_bound_keep_the_closed_form(formulation):
    """The disk's rest-to-rest rotation with the torque's effort weighted by W and the final
    angle only bounded below by PHI: turning farther costs more, so the optimum stops at PHI
    with the same torque, and costs W times the unweighted closed form."""
    j, phi, horizon, weight = 0.5, 1.0, 2.0, 3.0
    problem = OCP([Control("spin", "torque")], horizon=horizon, intervals=8,
                  terminal={"spin.angle_dot": 0.0}, terminal_bounds={"spin.angle": (phi, 3.0)},
                  weights={"spin.torque": weight}, formulation=formulation)
    model = casmech.loads(DISK)
    solution = solve(model, problem, "collocation")
    # piecewise-constant torques: the discrete optimum of the same functional, which the
    # continuous one bounds from below; the final angle on its bound (IPOPT's tolerance)
    end = columns_at(model, problem, solution, ["spin.angle"])[-1, 0]
    np.testing.assert_allclose(end, phi, rtol=0, atol=1e-7)
    closed = weight * 12 * j ** 2 * phi ** 2 / horizon ** 3
    assert closed <= solution.objective <= closed * 1.02  # N = 8 steps of a linear torque
    with pytest.raises(UsageError, match="not a control"):
        solve(model, OCP(**{**problem.__dict__, "weights": {"spin.force": 1.0}}),
              "collocation")


def test_a_decision_parameter_takes_its_closed_form_optimum():
    """The disk's inertia J among the unknowns, J in [0.2, 1]: the cost 12 J^2 PHI^2 / T^3
    falls with J, so the optimum is J = 0.2 with that J's closed-form torque."""
    phi, horizon = 1.0, 2.0
    problem = OCP([Control("spin", "torque")], horizon=horizon, intervals=8,
                  terminal={"spin.angle": phi, "spin.angle_dot": 0.0}, piecewise="linear",
                  parameters={"J": (0.2, 1.0)})
    solution = solve(casmech.loads(DISK), problem, "collocation")
    assert solution.formulation == "joints"
    # IPOPT's bound tolerance (tol 1e-10; its bound relaxation is 1e-8 relative)
    np.testing.assert_allclose(solution.design, [0.2], rtol=0, atol=1e-7)
    torque = 6 * 0.2 * phi / horizon ** 2 * (1 - 2 * solution.times / horizon)
    np.testing.assert_allclose(solution.u[:, 0], torque, rtol=0, atol=1e-6)  # N m, as above
    np.testing.assert_allclose(solution.objective, 12 * 0.2 ** 2 * phi ** 2 / horizon ** 3,
                               rtol=1e-6, atol=0)
    with pytest.raises(UsageError, match="neither a parameter"):
        solve(casmech.loads(DISK), OCP(**{**problem.__dict__, "parameters": {"K": (0, 1)}}),
              "collocation")


def test_body_coordinate_settings_choose_bodies():
    """stabilized or the interpolated guess (settings of the body transcription): auto takes
    body coordinates, joints says which setting it does not take."""
    model = casmech.load(MODELS / "ocp_pendulum_swing_up.yaml")
    problem, _ = from_block(model.ocp)
    assert joints_of(model, problem) is not None
    for setting in ({"stabilized": True}, {"initial_guess": "interpolation"}):
        assert joints_of(model, OCP(**{**problem.__dict__, **setting})) is None
        with pytest.raises(UsageError, match="does not take"):
            joints_of(model, OCP(**{**problem.__dict__, **setting, "formulation": "joints"}))


def test_a_partly_free_initial_state_takes_its_closed_form_optimum():
    """The disk starts at rest anywhere in [-0.2, 0.2] rad (initial_free with an equality and
    a bound on results columns) and must reach PHI at rest: the optimum starts at 0.2 and
    turns by PHI - 0.2 with that rotation's closed-form torque and cost."""
    j, phi, horizon = 0.5, 1.0, 2.0
    problem = OCP([Control("spin", "torque")], horizon=horizon, intervals=8,
                  terminal={"spin.angle": phi, "spin.angle_dot": 0.0}, piecewise="linear",
                  initial_free=True, initial={"spin.angle_dot": 0.0},
                  initial_bounds={"spin.angle": (-0.2, 0.2)})
    model = casmech.loads(DISK)
    solution = solve(model, problem, "shooting")
    start = columns_at(model, problem, solution, ["spin.angle", "spin.angle_dot"])[0]
    np.testing.assert_allclose(start, [0.2, 0.0], rtol=0, atol=1e-7)  # IPOPT's tolerance
    turn = phi - 0.2
    torque = 6 * j * turn / horizon ** 2 * (1 - 2 * solution.times / horizon)
    np.testing.assert_allclose(solution.u[:, 0], torque, rtol=0, atol=1e-6)  # as above
    np.testing.assert_allclose(solution.objective, 12 * j ** 2 * turn ** 2 / horizon ** 3,
                               rtol=1e-6, atol=0)
    with pytest.raises(UsageError, match="initial_free"):
        solve(model, OCP(**{**problem.__dict__, "initial_free": False}), "collocation")
    with pytest.raises(UsageError, match="joint coordinates only"):
        solve(model, OCP(**{**problem.__dict__, "formulation": "bodies"}), "collocation")
