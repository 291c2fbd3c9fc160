"""The joint formulation's equations of motion (compiler/joint_system.py, the recursions of
compiler/articulated.py) against the r-p ones.

At random joint states, the tree's poses and velocities satisfy every joint, and its
accelerations and multipliers must be the solution of the r-p saddle-point system
[M Phi_q^T; Phi_q 0] [q_ddot; lam] = [Q; gamma] at that state (an independent formulation:
Euler parameters, constraint rows, no recursion).
"""

import sys

import numpy as np
import pytest

import casmech
from casmech.compiler.joint_system import build
from casmech.compiler.tree import spanning_tree
from casmech.joint_types import MOTIONS
from casmech.runtime import assembly
from tests.conftest import MODELS, ROOT

ZOO = ROOT / "tests" / "runtime" / "joint_zoo.yaml"
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
