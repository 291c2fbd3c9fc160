"""A spherical joint's results states (equations/joint_states.py: e0 .. e3, wx .. wz) as one
traced step per joint, read once per joint by the results row (equations/readings.py): equal
to the same formulas run directly on the SX (core.traced_steps.direct) and to each state read
on its own through coordinates.JOINT_VALUES (the path force laws take). The formulas
themselves are checked against closed forms in tests/validation/runtime/test_joint_columns.py."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.core import traced_steps
from casmech.equations import coordinates, readings
from casmech.equations.joint_states import SPHERICAL_STATES
from casmech.equations.symbols import Coordinates
from casmech.model.bindings import coordinate_geometry
from tests.conftest import MODELS
from tests.unit.formulations.test_joint_system import chain_text

CASES = {"slider_crank": lambda: casmech.load(MODELS / "slider_crank.yaml"),
         "chain": lambda: casmech.loads(chain_text(5))}


def _unit_quaternions(q: np.ndarray, n_bodies: int) -> np.ndarray:
    """q with every body's Euler parameters made unit, as a state's are."""
    p = q[3 * n_bodies:].reshape(n_bodies, 4)
    q[3 * n_bodies:] = (p / np.linalg.norm(p, axis=1, keepdims=True)).reshape(-1)
    return q


@pytest.mark.parametrize("case", sorted(CASES))
def test_spherical_states_traced_equal_direct_and_one_by_one(case):
    ir = casmech.compile(CASES[case](), "interpreted").ir
    spherical = [k for k, joint in enumerate(ir.joints) if joint.type == "spherical"]
    assert spherical, "the case must have a spherical joint"
    with traced_steps.direct():
        direct = readings.columns_function(ir)
    steps = readings.columns_function(ir)
    # each state read on its own (coordinates.JOINT_VALUES), ground's pose substituted
    x = Coordinates.create(ir.n_bodies)
    alone = ca.Function("alone", [x.q, x.q_dot], [x.ground_fixed(ca.vertcat(*(
        coordinates.JOINT_VALUES[name](coordinate_geometry(ir.joints[k]), x)
        for k in spherical for name in SPHERICAL_STATES)))])
    names = readings.names(ir)
    rows = [names.index(f"{ir.joints[k].name}.{name}")
            for k in spherical for name in SPHERICAL_STATES]
    rng = np.random.default_rng(3)
    for _ in range(3):
        args = [rng.uniform(-1, 1, steps.sparsity_in(k).shape) for k in range(steps.n_in())]
        args[1] = _unit_quaternions(args[1].reshape(-1), ir.n_bodies)
        got, want = np.array(steps(*args).full()), np.array(direct(*args).full())
        # the same operations, evaluated in a step or on the SX directly: round-off
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
        one_by_one = np.array(alone(args[1], args[2]).full())
        # the same step evaluated per state: identical arithmetic
        np.testing.assert_allclose(got[rows], one_by_one, rtol=0, atol=1e-14)
