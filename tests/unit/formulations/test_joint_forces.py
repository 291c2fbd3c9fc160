"""Joint-local applied forces (formulations/joint_forces.py: the elements between the two bodies
of one tree joint as generalized forces on its coordinates) against the body-wrench evaluation
of the same elements (`joint_local=False`: every applied force a body wrench on the r-p
coordinates of the tree's state, a second formulation of their generalized forces), and a run
of the joint formulation against the r-p formulation's."""

import casadi as ca
import numpy as np
import pytest
import yaml

import casmech
from casmech.formulations import joint_forces
from casmech.formulations.joint_space import functions as joint_space_functions
from casmech.formulations.joint_system import build
from casmech.formulations.tree import spanning_tree
from tests.conftest import MODELS
from tests.unit.formulations.test_joint_ode_jacobian import ad_jacobian, robot_ir

RNG = np.random.default_rng(6)


def local_names(ir, tree) -> set[str]:
    return {e.name for elements in joint_forces.split(ir, tree).local for e in elements}


def states(system, ir, count: int) -> list:
    """(t, x) at random states, half of them with every stopped joint past a bound (inside
    the stop: its law's active branch)."""
    lay, tree = system.layout, system.tree
    found = []
    for k in range(count):
        x = RNG.uniform(-0.8, 0.8, lay.n_x)
        x[lay.n_theta:] = RNG.uniform(-2, 2, lay.n_x - lay.n_theta)
        if k % 2:
            for limit in ir.limits:
                index = next(i for i, j in enumerate(tree.joints) if j.name == limit.name)
                sign = -1.0 if tree.joints[index].reversed else 1.0
                lower, upper = limit.params["lower"], limit.params["upper"]
                past = upper + 0.01 if np.isfinite(upper) else lower - 0.01
                if np.isfinite(lower) and RNG.uniform() < 0.5:
                    past = lower - 0.01
                x[lay.theta[index][0]] = sign * past
        found.append((RNG.uniform(0, 2), x))
    return found


def assert_same_system(ir, count: int = 6) -> None:
    """The ODE, its Jacobian (the RNEA identity and CasADi's AD of the ODE) and the results
    row's (q, q_dot, q_ddot, lam) with the local elements in joint coordinates equal those with
    them as body wrenches."""
    tree = spanning_tree(ir)
    local, wrenches = build(ir, tree), build(ir, tree, joint_local=False)
    signs = np.ones(ir.n_bodies)
    for t, x in states(local, ir, count):
        pairs = [(local.dynamics(t, x), wrenches.dynamics(t, x))]
        pairs += zip(local.identity_jacobian()(t, x, local.dynamics(t, x)),
                     wrenches.identity_jacobian()(t, x, wrenches.dynamics(t, x)), strict=True)
        pairs += zip(ad_jacobian(local)(t, x), ad_jacobian(wrenches)(t, x), strict=True)
        pairs += zip(local.motion(t, x, ca.DM(0, 1), signs),
                     wrenches.motion(t, x, ca.DM(0, 1), signs), strict=True)
        for a, b in pairs:
            b = np.array(b)
            # one generalized force by two evaluations (its law on the joint's own frames, or
            # on the bodies' r-p coordinates through the chain): roundoff, 1e-10 of the
            # largest entry
            np.testing.assert_allclose(np.array(a), b, rtol=0,
                                       atol=1e-10 * max(np.max(np.abs(b), initial=0), 1.0))


def damped_and_stopped(ir, tmp_path):
    """A robot whose URDF declares neither (the UR5) with an rsda damper and a stop on every
    revolute joint, as the importer writes `<dynamics damping>` and `<limit>`."""
    model = yaml.safe_load(open(ir.file).read())
    for joint in model["joints"]:
        if joint["type"] == "revolute":
            joint["limit"] = {"lower": -1.0, "upper": 1.0, "stiffness": 2000.0, "damping": 5.0}
            model.setdefault("forces", []).append(
                {"name": f"{joint['name']}_damping", "type": "rsda", "joint": joint["name"],
                 "damping": 0.5})
    path = tmp_path / "damped.yaml"
    path.write_text(yaml.safe_dump(model, sort_keys=False))
    return casmech.compile(casmech.load(path), "interpreted").ir


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_imported_robots_damping_and_stops_in_joint_coordinates(name, tmp_path, monkeypatch):
    """The importer's `<dynamics damping>` (rsda, a tsda along a prismatic finger's axis) and
    limit stops of every joint are local; the ODE, its Jacobian and the results row are the
    body-wrench evaluation's."""
    ir = robot_ir(name, tmp_path, monkeypatch)
    if not ir.limits:
        ir = damped_and_stopped(ir, tmp_path)
    tree = spanning_tree(ir)
    assert ir.limits and {e.name for e in ir.limits} <= local_names(ir, tree)
    assert {e.name for e in ir.forces} <= local_names(ir, tree)
    assert_same_system(ir)


def flyball_with_stop(tmp_path):
    """The gallery's flyball governor (rsda dampers in the arms' hinges, the spindle driven)
    with a stop on one hinge and a tsda along the axis of a prismatic joint added."""
    model = yaml.safe_load((MODELS / "flyball_governor.yaml").read_text())
    hinge = next(j for j in model["joints"] if j["name"] == "hinge_a")
    hinge["limit"] = {"lower": -0.2, "upper": 0.3, "stiffness": 500.0, "damping": 3.0}
    path = tmp_path / "flyball_stop.yaml"
    path.write_text(yaml.safe_dump(model, sort_keys=False))
    return casmech.compile(casmech.load(path), "interpreted").ir


def test_gallery_rsda_and_stop(tmp_path):
    ir = flyball_with_stop(tmp_path)
    tree = spanning_tree(ir)
    # the driven spindle's joint has none; the hinges' dampers and the stop are local
    assert local_names(ir, tree) == {"damper_a", "damper_b", "hinge_a"}
    system = build(ir, tree)
    k = next(i for i, j in enumerate(tree.joints) if j.name == "hinge_a")
    stop = joint_forces.local_torque(tree.joints[k], tuple(ir.limits))
    pushed = [float(stop(x[system.layout.theta[k][0]], x[system.layout.u[k][0]], t))
              for t, x in states(system, ir, 4)[1::2]]
    assert all(abs(f) > 1 for f in pushed)  # the states past a bound are inside the stop
    assert_same_system(ir)


def test_joint_space_functions(tmp_path, monkeypatch):
    """forward_dynamics, inverse_dynamics and their derivatives (what the benchmark calls)
    with the local elements in joint coordinates equal the body-wrench evaluation's."""
    ir = robot_ir("panda", tmp_path, monkeypatch)
    tree = spanning_tree(ir)
    local, wrenches = (joint_space_functions(ir, tree, joint_local=flag) for flag in (True, False))
    nq = local["forward_dynamics"].size1_in(1)
    for _ in range(3):
        t, q, v, tau = RNG.uniform(0, 1), *RNG.uniform(-2, 2, (3, nq))
        for name in ("forward_dynamics", "inverse_dynamics", "bias_forces",
                     "forward_dynamics_derivatives", "inverse_dynamics_derivatives"):
            args = (t, q, v, tau)[:local[name].n_in()]
            for a, b in zip(local[name].call(list(args)), wrenches[name].call(list(args)),
                            strict=True):
                b = np.array(b)
                # as assert_same_system
                np.testing.assert_allclose(np.array(a), b, rtol=0,
                                           atol=1e-10 * max(np.max(np.abs(b), initial=0), 1))


def test_elements_that_stay_body_wrenches(tmp_path):
    """A force whose law reads another joint's state, and the elements of a driven joint,
    stay body wrenches; a tsda between a tree joint's bodies (off its axis: the reactions
    come from its body wrenches) and an effort motor whose law reads t and its own angle are
    local."""
    model = yaml.safe_load((MODELS / "flyball_governor.yaml").read_text())
    hinge = next(j for j in model["joints"] if j["name"] == "hinge_b")
    hinge["motor"] = {"torque": "0.3 * sin(2 * t) - 0.5 * angle - 0.1 * angle_dot"}
    model["forces"] += [
        {"name": "reads_other", "type": "rsda", "joint": "hinge_b",
         "actuator": "0.1 * hinge_a.angle"},
        {"name": "on_driven", "type": "rsda", "joint": "spindle_bearing", "damping": 0.1},
        {"name": "spring", "type": "tsda", "body_i": "spindle", "at_i": [0, 0, 0.2],
         "body_j": "arm_a", "at_j": ["r0", 0, "H - l * cos(alpha0)"], "stiffness": 50.0}]
    path = tmp_path / "flyball_more.yaml"
    path.write_text(yaml.safe_dump(model, sort_keys=False))
    ir = casmech.compile(casmech.load(path), "interpreted").ir
    assert local_names(ir, spanning_tree(ir)) == {"damper_a", "damper_b", "spring", "hinge_b"}
    assert_same_system(ir, count=4)


def test_run_is_the_rp_run(tmp_path):
    """A dynamics run of the flyball governor with its stop, joint formulation (the local
    elements in joint coordinates) against the r-p formulation (every force a body wrench):
    one results table (motion, reactions, the stop's columns) to the runs' tolerance."""
    flyball_with_stop(tmp_path)
    functions = casmech.compile(casmech.load(tmp_path / "flyball_stop.yaml"), "interpreted")
    tables = {}
    for formulation in ("joint", "rp"):
        run = casmech.analyze(functions, formulation=formulation, t_end=1.0, rtol=1e-10,
                              atol=1e-12)
        names, tables[formulation] = casmech.results_table(functions, run)
    names = list(names)
    joint, rp = (np.asarray(tables[f]) for f in ("joint", "rp"))
    assert np.min(rp[:, names.index("hinge_a.limit_gap")]) < -1e-3  # the arm enters the stop
    scale = np.maximum(1.0, np.max(np.abs(rp), axis=0))
    # two formulations integrated at rtol 1e-10: they differ by their errors (reactions of
    # ~100 N through the stop to 1e-6 of their scale)
    np.testing.assert_allclose(joint / scale, rp / scale, rtol=0, atol=1e-6, err_msg=str(names))


def test_parametric_build_with_local_elements(tmp_path):
    """A build over the model data (model.parametric.split: the hinges' damping and the arms'
    length as data, the stop's bounds too) bound to a value's data equals the numeric build
    of the IR lowered at that value: the local elements' laws read the data input."""
    from casmech.model import parametric
    from casmech.model.lower import lower

    flyball_with_stop(tmp_path)
    text = (tmp_path / "flyball_stop.yaml").read_text()
    split = parametric.split(lower(casmech.loads(text)))
    symbolic = build(split.ir, spanning_tree(split.ir), split.symbols)
    assert local_names(split.ir, spanning_tree(split.ir)) == {"damper_a", "damper_b", "hinge_a"}
    for given in ({"c": "0.5", "l": "0.35"}, {"c": "1.5", "m": "2.0"}):
        ir = lower(casmech.loads(text, overrides=given))
        numeric = build(ir, spanning_tree(ir))
        joint_data = symbolic.data(parametric.data(ir)[0])
        for t, x in states(numeric, ir, 4):
            pairs = [(symbolic.dynamics(t, x, joint_data), numeric.dynamics(t, x))]
            pairs += zip(symbolic.motion(t, x, ca.DM(0, 1), np.ones(ir.n_bodies), joint_data),
                         numeric.motion(t, x, ca.DM(0, 1), np.ones(ir.n_bodies)), strict=True)
            for a, b in pairs:
                b = np.array(b)
                # the same arithmetic but for the constants' association: roundoff
                np.testing.assert_allclose(np.array(a), b, rtol=0,
                                           atol=1e-12 * max(np.max(np.abs(b), initial=0), 1))


def test_loop_dae_with_local_elements():
    """A tree with a cut joint (the free four-bar of test_joint_system: its universal joint
    cut) with an rsda on the crank's pivot and a stop on the rocker's: the DAE, its
    acceleration system and the results row (the cut rows' multipliers from z, the tree
    joints' from the subtree balance) equal the body-wrench evaluation's at random (t, x, z,
    p)."""
    from tests.unit.formulations.test_joint_system import free_four_bar

    model = yaml.safe_load(free_four_bar())
    pivot = next(j for j in model["joints"] if j["name"] == "rocker_pivot")
    pivot["limit"] = {"lower": -0.3, "upper": 0.2, "stiffness": 800.0, "damping": 4.0}
    model["forces"] = [{"name": "spring", "type": "rsda", "joint": "crank_pivot",
                        "stiffness": 20.0, "damping": 0.5, "free_angle": 0.2}]
    ir = casmech.compile(casmech.loads(yaml.safe_dump(model, sort_keys=False)),
                         "interpreted").ir
    tree = spanning_tree(ir)
    assert tree.cut and local_names(ir, tree) == {"spring", "rocker_pivot"}
    local, wrenches = build(ir, tree), build(ir, tree, joint_local=False)
    for t, x in states(local, ir, 6):
        z = RNG.uniform(-5, 5, local.dynamics.size1_in(2))
        p = RNG.integers(0, 2, local.dynamics.size1_in(3))
        pairs = list(zip(local.dynamics(t, x, z, p), wrenches.dynamics(t, x, z, p),
                         strict=True))
        pairs += zip(local.acceleration_system(t, x), wrenches.acceleration_system(t, x),
                     strict=True)
        pairs += zip(local.motion(t, x, z, np.ones(ir.n_bodies)),
                     wrenches.motion(t, x, z, np.ones(ir.n_bodies)), strict=True)
        for a, b in pairs:
            b = np.array(b)
            # as assert_same_system
            np.testing.assert_allclose(np.array(a), b, rtol=0,
                                       atol=1e-10 * max(np.max(np.abs(b), initial=0), 1))
