"""runtime.joint_space_calls: a joint space's NumPy calls through buffers give what CasADi's
own call of the same functions gives, bit for bit, from one thread or several."""

import sys
import threading

import numpy as np
import pytest

import casmech
from casmech.formulations import joint_space as joint_spaces
from casmech.model.lower import lower
from tests.conftest import MODELS


def _arguments(space, rng):
    q = space.neutral + 0.3 * rng.standard_normal(space.nq)
    v, tau = rng.standard_normal(space.nv), rng.standard_normal(space.nv)
    return q, v, tau


def test_the_buffered_calls_equal_casadis_calls():
    # a spherical joint (nq > nv, quaternion coordinates) and revolute ones; the derivatives
    # are structurally sparse, the buffered ones dense
    ir = lower(casmech.load(MODELS / "heavy_top.yaml"))
    plain, buffered = joint_spaces.joint_space(ir), casmech.joint_space(casmech.load(
        MODELS / "heavy_top.yaml"))
    assert type(plain.calls).__name__ == "_CasadiCalls" and type(buffered.calls).__name__ == "Calls"
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, v, tau = _arguments(plain, rng)
        pairs = [(plain.mass_matrix(q), buffered.mass_matrix(q)),
                 (plain.bias_forces(q, v), buffered.bias_forces(q, v)),
                 (plain.forward_dynamics(q, v, tau), buffered.forward_dynamics(q, v, tau)),
                 (plain.inverse_dynamics(q, v, tau), buffered.inverse_dynamics(q, v, tau)),
                 *zip(plain.forward_dynamics_derivatives(q, v, tau),
                      buffered.forward_dynamics_derivatives(q, v, tau), strict=True),
                 *zip(plain.inverse_dynamics_derivatives(q, v, tau),
                      buffered.inverse_dynamics_derivatives(q, v, tau), strict=True),
                 *zip(plain.forward_kinematics(q, v), buffered.forward_kinematics(q, v),
                      strict=True)]
        for expected, found in pairs:
            assert found.shape == expected.shape
            np.testing.assert_array_equal(found, expected)  # the same SX evaluated


def test_threads_share_a_space():
    # threads switched as often as the interpreter allows: two calls overlapping in one
    # function's buffers would mix their arguments
    switch = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        _threads_share_a_space()
    finally:
        sys.setswitchinterval(switch)


def _threads_share_a_space():
    space = casmech.joint_space(casmech.load(MODELS / "double_pendulum.yaml"))
    rng = np.random.default_rng(5)
    cases = [_arguments(space, rng) for _ in range(8)]
    expected = [space.forward_dynamics_derivatives(*case)[0] for case in cases]
    failures = []

    def work(k: int) -> None:
        for _ in range(300):
            found = space.forward_dynamics_derivatives(*cases[k])[0]
            if not np.array_equal(found, expected[k]):
                failures.append(k)
                return

    threads = [threading.Thread(target=work, args=(k,)) for k in range(len(cases))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert failures == []


def test_lists_are_arguments_and_a_wrong_size_is_named():
    space = casmech.joint_space(casmech.load(MODELS / "double_pendulum.yaml"))
    q, v, tau = np.array([0.3, -0.2]), np.array([0.5, 1.0]), np.array([0.1, 0.0])
    np.testing.assert_array_equal(space.forward_dynamics(list(q), list(v), list(tau)),
                                  space.forward_dynamics(q, v, tau))  # the same numbers in
    np.testing.assert_array_equal(space.forward_dynamics(q[:, None], v, tau),
                                  space.forward_dynamics(q, v, tau))  # a column is a vector
    with pytest.raises(ValueError, match=r"forward_dynamics: q takes 2 numbers, got \(3,\)"):
        space.forward_dynamics([0.1, 0.2, 0.3], v, tau)
    with pytest.raises(ValueError, match="mass_matrix: q takes 2 numbers, got 'x'"):
        space.mass_matrix("x")


def test_every_call_gives_fresh_arrays():
    space = casmech.joint_space(casmech.load(MODELS / "double_pendulum.yaml"))
    q, v, tau = np.array([0.3, -0.2]), np.array([0.5, 1.0]), np.array([0.1, 0.0])
    kept = [space.forward_dynamics(q, v, tau), *space.forward_dynamics_derivatives(q, v, tau),
            space.mass_matrix(q)]
    copies = [array.copy() for array in kept]
    space.forward_dynamics(q + 1, v, tau)
    space.forward_dynamics_derivatives(q + 1, v, tau)
    space.mass_matrix(q + 1)
    for array, copy in zip(kept, copies, strict=True):
        np.testing.assert_array_equal(array, copy)  # a later call writes none of them


def test_every_layout_of_the_same_numbers_gives_the_same_result():
    space = casmech.joint_space(casmech.load(MODELS / "double_pendulum.yaml"))
    q, v, tau = np.array([1.0, -2.0]), np.array([0.5, 1.0]), np.array([0.1, 0.0])
    expected = space.forward_dynamics(q, v, tau)
    layouts = [(q[:, None], v, tau, 0.0), (q[None, :], v, tau, 0.0),  # a column, a row
               (np.repeat(q, 2)[::2], v, tau, 0.0),  # strided
               (np.array([1, -2]), v, tau, 0.0), (list(q), tuple(v), tau, 0),  # integers
               (q, v, tau, np.float64(0.0)), (q, v, tau, [0.0]), (q, v, tau, np.array(0.0))]
    for q_, v_, tau_, t in layouts:
        np.testing.assert_array_equal(space.forward_dynamics(q_, v_, tau_, t=t), expected)


def test_a_number_is_not_spread_over_a_vector():
    space = casmech.joint_space(casmech.load(MODELS / "double_pendulum.yaml"))
    v, tau = np.array([0.5, 1.0]), np.array([0.1, 0.0])
    with pytest.raises(ValueError, match="forward_dynamics: q takes 2 numbers, got 0.5"):
        space.forward_dynamics(0.5, v, tau)
    with pytest.raises(ValueError, match=r"forward_dynamics: v takes 2 numbers, got \(1,\)"):
        space.forward_dynamics(v, np.array([0.5]), tau)
    with pytest.raises(ValueError, match=r"forward_dynamics: t takes 1 number, got \(2,\)"):
        space.forward_dynamics(v, v, tau, t=[0.0, 1.0])
    np.testing.assert_array_equal(space.forward_dynamics(v, v, tau), space.forward_dynamics(
        v, v, tau, t=0.0))  # the failed calls left nothing behind
