"""A spherical joint's results states (equations/joint_states.py: e0 .. e3, wx .. wz) as one
traced step per joint (the results row reads them mapped over the joints:
equations/readings.py): equal to the same formulas run directly on the SX
(core.traced_steps.direct) and to each state read on its own through coordinates.JOINT_VALUES
(the path force laws take). The formulas themselves are checked against closed forms in
tests/validation/runtime/test_joint_columns.py."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.core import traced_steps
from casmech.equations import coordinates, joint_states, readings
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


@pytest.mark.parametrize("case", sorted(CASES))
def test_spherical_states_mapped_over_joints_equal_each_joints_own(case):
    """The results row reads every spherical joint's states from one mapped call
    (joint_states.spherical_states_of): bitwise the traced step's per joint, and the formulas
    run directly on the SX up to round-off (a joint on ground included)."""
    ir = casmech.compile(CASES[case](), "interpreted").ir
    geometries = [coordinate_geometry(joint) for joint in ir.joints if joint.type == "spherical"]
    x = Coordinates.create(ir.n_bodies)
    mapped = joint_states.spherical_states_of(geometries, x)
    assert list(mapped) == [g.name for g in geometries]

    def function(states):
        return ca.Function("f", [x.q, x.q_dot], [x.ground_fixed(ca.vertcat(*(
            states[g.name][name] for g in geometries for name in SPHERICAL_STATES)))])
    each = {g.name: joint_states.spherical_states(g, x) for g in geometries}
    with traced_steps.direct():
        direct = {g.name: joint_states.spherical_states(g, x) for g in geometries}
    rng = np.random.default_rng(4)
    for _ in range(3):
        q = _unit_quaternions(rng.uniform(-1, 1, 7 * ir.n_bodies), ir.n_bodies)
        q_dot = rng.uniform(-1, 1, 7 * ir.n_bodies)
        got = np.array(function(mapped)(q, q_dot).full())
        # the same step on the same arguments: identical arithmetic
        np.testing.assert_array_equal(got, np.array(function(each)(q, q_dot).full()))
        # the same operations in a step or on the SX directly: round-off
        np.testing.assert_allclose(got, np.array(function(direct)(q, q_dot).full()),
                                   rtol=1e-12, atol=1e-12)
