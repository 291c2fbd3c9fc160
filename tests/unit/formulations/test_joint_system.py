"""The joint formulation's equations of motion (formulations/joint_system.py, the recursions of
formulations/articulated.py) against the r-p ones.

At random joint states, the tree's poses and velocities satisfy every joint, and its
accelerations and multipliers must be the solution of the r-p saddle-point system
[M Phi_q^T; Phi_q 0] [q_ddot; lam] = [Q; gamma] at that state (an independent formulation:
Euler parameters, constraint rows, no recursion).
"""

import sys

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.elements.joint_types import MOTIONS
from casmech.formulations.joint_system import build
from casmech.formulations.tree import spanning_tree
from casmech.runtime import assembly
from tests.conftest import MODELS, ROOT

ZOO = ROOT / "tests" / "helpers" / "joint_zoo.yaml"
RNG = np.random.default_rng(3)


def random_state(system) -> np.ndarray:
    x = RNG.uniform(-0.8, 0.8, system.layout.n_x)
    for joint, index, free in zip(system.tree.joints, system.layout.theta,
                                  system.layout.free_theta, strict=True):
        for start in MOTIONS[joint.type].quaternions:
            block = [index[free.index(c)] for c in range(start, start + 4)]
            x[block] /= np.linalg.norm(x[block])
    return x


@pytest.mark.parametrize("path", [ZOO, MODELS / "quadruped_legs.yaml",
                                  MODELS / "chain_repeat.yaml"], ids=lambda p: p.stem)
def test_accelerations_and_multipliers_solve_the_rp_equations(path):
    functions = casmech.compile(casmech.load(path))
    system = build(functions.ir, spanning_tree(functions.ir))
    nb, m = functions.n_bodies, functions.n_joint_rows
    for t in (0.0, 0.37):
        x = random_state(system)
        q, q_dot, q_ddot, lam = (np.array(out.full()).ravel()
                                 for out in system.motion(t, x, [], np.ones(nb)))
        # the state satisfies every joint: position and velocity constraints to roundoff
        np.testing.assert_allclose(functions.vector("phi", t, q), 0, rtol=0, atol=1e-12)
        velocity = functions.matrix("phi_q", t, q) @ q_dot - functions.vector("nu", t, q)
        np.testing.assert_allclose(velocity, 0, rtol=0, atol=1e-11)
        expected, multipliers = assembly.solve_dynamic_accelerations(functions, t, q, q_dot)
        # both solve the same linear equations in double precision (the r-p saddle point has
        # condition ~1e4-1e6 here): agreement to 1e-8 of the acceleration scale
        scale = np.max(np.abs(expected))
        np.testing.assert_allclose(q_ddot, expected, rtol=0, atol=1e-8 * scale)
        np.testing.assert_allclose(lam[:m], multipliers[:m], rtol=0,
                                   atol=1e-8 * np.max(np.abs(multipliers[:m])))


def test_long_chain_stays_accurate():
    """48 bars with a 1e-4 axial inertia, bent at random: the articulated inertia of each
    spherical joint is eliminated blockwise, so the roundoff does not grow along the chain
    (the generic IA - U D^-1 U^T gave accelerations 1.6e-2 off here, growing ~2.5x per body)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import casmech_model
    import systems

    functions = casmech.compile(casmech.loads(casmech_model.yaml_text(systems.chain(48))))
    system = build(functions.ir, spanning_tree(functions.ir))
    x = random_state(system)
    q, q_dot, q_ddot, _ = (np.array(out.full()).ravel()
                           for out in system.motion(0.0, x, [], np.ones(48)))
    expected, _ = assembly.solve_dynamic_accelerations(functions, 0.0, q, q_dot)
    # measured 4e-12 of the scale; the saddle-point solve itself is good to ~1e-11 here
    np.testing.assert_allclose(q_ddot, expected, rtol=0, atol=1e-9 * np.max(np.abs(expected)))


def free_four_bar() -> str:
    """models/four_bar.yaml (revolute, spherical, universal, revolute; link lengths a, b, c,
    d as parameters) without its crank driver, swinging under gravity: one DOF, a loop."""
    text = (MODELS / "four_bar.yaml").read_text()
    text = text.replace("    driver:\n      angle: omega * t\n", "")
    text = text.replace("output_step: 0.01", "output_step: 0.01\n  rtol: 1.0e-8\n  atol: 1.0e-10")
    return text.replace("analysis:\n  type: inverse_dynamics",
                        "gravity: [0, -9.81, 0]\n\nanalysis:\n  type: dynamics")


PARAMETRIC_CASES = {
    # a tree: masses and lengths (the joint points, the inertias)
    "double_pendulum": ((MODELS / "double_pendulum.yaml").read_text(),
                        [{"m1": "2.0", "L2": "1.3"}, {"m2": "0.4", "L1": "0.7"}]),
    # a loop: the coupler's length moves the closure and the universal joint's frames
    "four_bar": (free_four_bar(), [{"b": "2.2"}, {"b": "1.9", "m": "1.5"}]),
    # a coupling: the gear's row a closure row over both pinions, the pivot's place and the
    # bob's mass and arm as data
    "gear_pair": ((MODELS / "gear_pair.yaml").read_text(),
                  [{"m": "0.7", "l": "0.25"}, {"r1": "0.06", "r2": "0.18"}]),
}


@pytest.mark.parametrize("case", PARAMETRIC_CASES)
def test_joint_functions_with_the_model_data_equal_the_numeric_ones(case):
    """build over model.parametric.split's IR, bound to each value's data through
    JointSystem.data, equals build over the IR lowered at that value, at random (t, x, z)."""
    from casmech.model import parametric
    from casmech.model.lower import lower
    from casmech.numerics import lazy_jacobian

    text, values = PARAMETRIC_CASES[case]
    split = parametric.split(lower(casmech.loads(text)))
    symbolic = build(split.ir, spanning_tree(split.ir), split.symbols)
    rng = np.random.default_rng(5)
    for given in values:
        ir = lower(casmech.loads(text, overrides=given))
        model_data, signature = parametric.data(ir)
        assert signature == split.signature  # the same structure: one build serves both
        numeric = build(ir, spanning_tree(ir))
        joint_data = symbolic.data(model_data)
        pairs = {name: (getattr(numeric, name), getattr(symbolic, name)) for name in (
            "dynamics", "motion", "acceleration_system", "velocity_jacobian", "relative_states")}
        # the Jacobian a parametric library gives the integrators (by the states, not by d)
        pairs["jacobian"] = (numeric.dynamics.jacobian(),
                             lazy_jacobian.data_jacobian(symbolic.dynamics))
        for name, (want_f, got_f) in pairs.items():
            assert got_f.name_in() == [*want_f.name_in(), "d"]
            for _ in range(3):
                args = [rng.uniform(-1, 1, want_f.sparsity_in(k).shape)
                        for k in range(want_f.n_in())]
                if "p" in want_f.name_in():  # the DAE's row mask: 0 or 1
                    args[want_f.index_in("p")] = rng.integers(0, 2, want_f.size1_in("p"))
                got, want = got_f(*args, joint_data), want_f(*args)
                got, want = (got, want) if isinstance(got, tuple) else ((got,), (want,))
                for a, b in zip(got, want, strict=True):
                    b = np.array(b.full())
                    scale = max(1.0, float(np.max(np.abs(b), initial=0.0)))
                    # the same arithmetic but for the constants' association (computed from
                    # d at run time, folded at build time): round-off of the largest entry
                    # (the loop's acceleration residual, second derivatives through the
                    # recursion, cancels more: 1.5e-12 of its scale measured)
                    tol = 1e-11 if name == "acceleration_system" else 1e-12
                    np.testing.assert_allclose(np.array(a.full()), b, rtol=tol,
                                               atol=tol * scale, err_msg=f"{name} {given}")


TRACED_CASES = {"zoo": lambda: casmech.load(ZOO),
                "quadruped": lambda: casmech.load(MODELS / "quadruped_legs.yaml"),
                "chain": lambda: casmech.loads(chain_text(12)),
                "four_bar": lambda: casmech.loads(free_four_bar())}


def chain_text(n: int) -> str:
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import casmech_model
    import systems

    return casmech_model.yaml_text(systems.chain(n))


@pytest.mark.parametrize("case", TRACED_CASES)
def test_traced_steps_equal_the_steps_run_directly(case):
    """The recursions' per-body steps evaluated as traced Functions (core.traced_steps) give the
    functions the same code gives run on the SX directly, at random (t, x, z): branched trees,
    a chain, a loop."""
    from casmech.core import traced_steps as traced

    functions = casmech.compile(TRACED_CASES[case]())
    ir, tree = functions.ir, spanning_tree(functions.ir)
    with traced.direct():
        direct = build(ir, tree)
    steps = build(ir, tree)
    rng = np.random.default_rng(11)
    for name in ("dynamics", "motion", "acceleration_system", "velocity_jacobian",
                 "relative_states"):
        want_f, got_f = getattr(direct, name), getattr(steps, name)
        for _ in range(3):
            args = [rng.uniform(-1, 1, want_f.sparsity_in(k).shape) for k in range(want_f.n_in())]
            if "p" in want_f.name_in():  # the DAE's row mask: 0 or 1
                args[want_f.index_in("p")] = rng.integers(0, 2, want_f.size1_in("p"))
            got, want = got_f(*args), want_f(*args)
            got, want = (got, want) if isinstance(got, tuple) else ((got,), (want,))
            for a, b in zip(got, want, strict=True):
                b = np.array(b.full())
                scale = max(1.0, float(np.max(np.abs(b), initial=0.0)))
                # the same operations but for the association of products of constants
                # (folded when a step is evaluated): round-off of the largest entry, with the
                # loop's acceleration residual as in the test above
                tol = 1e-11 if name == "acceleration_system" else 1e-12
                np.testing.assert_allclose(np.array(a.full()), b, rtol=tol, atol=tol * scale,
                                           err_msg=name)


@pytest.mark.parametrize("path", [ZOO, MODELS / "four_bar.yaml", MODELS / "gear_pair.yaml"],
                         ids=lambda p: p.stem)
def test_each_joints_rows_equal_the_rp_bundles(path):
    """rows_of (one Function per row structure, the vectors and driver values as inputs) gives
    each joint's rows of phi and their r-omega Jacobians [Phi_r, Pi_bar] at every body they
    read as the r-p bundle's phi and variations (built over the whole system), at random poses
    and times: every joint type of the zoo, drivers, ground on either side, a gear's row over
    the bodies of two joints."""
    from casmech.formulations.joint_system import joint_bodies, rows_of

    functions = casmech.compile(casmech.load(path))
    ir, nb = functions.ir, functions.n_bodies
    rng = np.random.default_rng(7)
    for _ in range(3):
        t = rng.uniform(0, 2)
        q = rng.uniform(-1, 1, 7 * nb)
        p = q[3 * nb:].reshape(nb, 4)
        p /= np.linalg.norm(p, axis=1)[:, None]
        phi = functions.vector("phi", t, q)
        phi_r, pi_bar = functions.evaluate("variations", t, q)

        for joint in ir.joints:
            rows, bodies = list(joint.rows), joint_bodies(ir, joint)
            got = [np.array(ca.evalf(v)) for v in rows_of(
                ir, joint, t, *(v for k in bodies for v in _pose(q, p, k)))]
            assert len(got) == 1 + len(bodies)
            assert max(np.max(np.abs(block)) for block in got[1:]) > 0.1  # not all zero
            # the same primitives' arithmetic, differentiated per joint instead of over the
            # whole system: roundoff of O(1) entries
            np.testing.assert_allclose(got[0].ravel(), phi[rows], rtol=0, atol=1e-13)
            for k, block in zip(bodies, got[1:], strict=True):
                if k < 0:
                    continue
                want = np.hstack([phi_r[rows, 3 * k:3 * k + 3], pi_bar[rows, 3 * k:3 * k + 3]])
                np.testing.assert_allclose(block, want, rtol=0, atol=1e-13, err_msg=joint.name)
            if joint.couples:
                assert len(bodies) == 3  # ground and both gears


def _pose(q, p, k: int) -> tuple:
    """(r, p) of body k in q (ground's at the origin)."""
    return (np.zeros(3), np.array([1.0, 0, 0, 0])) if k < 0 else (q[3 * k:3 * k + 3], p[k])


def test_saddle_terms_over_the_model_data_are_the_numeric_ones():
    """saddle_terms of model.parametric.split's IR, called with the split's values, gives the
    numeric IR's terms (the tree's constants computed from d inside)."""
    from casmech.formulations.joint_system import saddle_terms
    from casmech.model.parametric import split

    functions = casmech.compile(casmech.load(MODELS / "four_bar_released.yaml"))
    tree = spanning_tree(functions.ir)
    parts = split(functions.ir)
    symbolic = saddle_terms(parts.ir, tree, data=parts.symbols)
    numeric = saddle_terms(functions.ir, tree)
    assert symbolic.name_in() == ["t", "x", "d"]
    for t in (0.0, 0.3):
        x = RNG.uniform(-0.8, 0.8, numeric.size1_in(1))
        for got, expected in zip(symbolic(t, x, parts.values), numeric(t, x), strict=True):
            # the same expressions, evaluated with the numbers as inputs or folded in
            np.testing.assert_allclose(np.array(got), np.array(expected), rtol=1e-12,
                                       atol=1e-12)
