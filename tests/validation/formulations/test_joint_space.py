"""casmech.joint_space (formulations.joint_space) against Pinocchio on robots imported from
example-robot-data's URDFs (both skipped without the packages): M(q) (crba), the bias forces
(nonLinearEffects plus the URDF's joint damping, which casmech's imported model applies),
forward and inverse dynamics (aba, rnea) and their derivatives (computeABADerivatives,
computeRNEADerivatives), at random states inside the joint limits; every tree joint type,
drivers and a free body against the r-p formulation of the same model: the accelerations, and
the recursive Newton-Euler inverse dynamics against M a + b with M the r-p mass matrix carried
to the joint space; the forward-dynamics derivatives (from the inverse dynamics' by
Carpentier and Mansard's identity) against CasADi's AD of the articulated-body algorithm."""

from __future__ import annotations

from importlib import metadata
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.errors import UsageError
from casmech.formulations.rnea import forward_derivatives
from casmech.importers.emit import to_yaml
from casmech.importers.urdf import import_urdf
from tests.conftest import MODELS, ROOT

ROBOTS = {"ur5": "ur_description/urdf/ur5_robot.urdf",
          "panda": "panda_description/urdf/panda.urdf",
          "kinova": "kinova_description/robots/kinova.urdf",
          "talos_arm": "talos_data/robots/talos_left_arm.urdf",
          "solo12": "solo_description/robots/solo12.urdf"}


def robots_folder() -> Path:
    try:
        distribution = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed (pip install example-robot-data)")
    return Path(distribution.locate_file("cmeel.prefix/share/example-robot-data"))


@pytest.fixture(params=sorted(ROBOTS))
def robot(request, tmp_path, monkeypatch):
    """(casmech JointSpace, pinocchio Model, casmech model) of one robot."""
    pin = pytest.importorskip("pinocchio")
    folder = robots_folder()
    path = folder / "robots" / ROBOTS[request.param]
    monkeypatch.setenv("CASMECH_ALLOWED_DIRS", str(folder))  # its meshes
    out = tmp_path / f"{request.param}.yaml"
    model = import_urdf(path, output=out)
    # Pinocchio's URDF parser leaves <mimic> out: the fingers' coupler is left out here too
    model.joints = [joint for joint in model.joints if joint.data["type"] != "coupler"]
    for joint in model.joints:  # the URDF's dry friction (Talos): no algorithm here applies it
        joint.data.pop("friction", None)
    out.write_text(to_yaml(model))
    loaded = casmech.load(out)
    return casmech.joint_space(loaded), pin.buildModelFromUrdf(str(path)), loaded


def states(model, count: int = 3):
    """Random (q, v, a, tau) in casmech's coordinates (one angle per joint) with q inside the
    limits (casmech's imported stops act outside), a continuous joint's angle in [-pi, pi]."""
    rng = np.random.default_rng(34)
    for _ in range(count):
        q = []
        for joint in list(model.joints)[1:]:
            if joint.nq == 1:
                low = model.lowerPositionLimit[joint.idx_q]
                high = model.upperPositionLimit[joint.idx_q]
                q.append(low + (high - low) * rng.uniform(0.1, 0.9))
            else:  # Pinocchio's continuous joint: (cos, sin) of an unbounded angle
                q.append(rng.uniform(-np.pi, np.pi))
        yield (np.array(q), *rng.uniform(-2, 2, (3, model.nv)))


def pinocchio_q(model, q: np.ndarray) -> np.ndarray:
    """Pinocchio's configuration of casmech's angles: a continuous joint's is (cos, sin)."""
    parts = [[angle] if joint.nq == 1 else [np.cos(angle), np.sin(angle)]
             for joint, angle in zip(list(model.joints)[1:], q, strict=True)]
    return np.concatenate(parts)


def symmetric(upper: np.ndarray) -> np.ndarray:
    return np.triu(upper) + np.triu(upper, 1).T  # Pinocchio fills M's upper triangle


def test_joint_space_matches_pinocchio(robot):
    import pinocchio as pin

    space, model, _ = robot
    data = model.createData()
    # Pinocchio orders joints depth first, casmech's tree breadth first (Solo12's legs); one
    # velocity per joint on these robots
    order = np.array([space.joints.index(model.names[k]) for k in range(1, model.njoints)])
    assert space.nq == space.nv == model.nv == len(order)
    assert sorted(order) == list(range(space.nv))
    ours = np.argsort(order)  # Pinocchio's vectors in casmech's order: x[ours]

    def theirs(x):  # casmech's vector or matrix in Pinocchio's order
        return x[order] if x.ndim == 1 else x[np.ix_(order, order)]

    damping = np.diag(model.damping)
    # two recursive algorithms in double precision on entries up to ~50: atol 1e-10
    tol = {"rtol": 1e-10, "atol": 1e-10}
    for angles, v_pin, a_pin, tau_pin in states(model):
        q_pin = pinocchio_q(model, angles)  # Pinocchio's derivatives: its tangent, d angle
        q, v, a, tau = angles[ours], v_pin[ours], a_pin[ours], tau_pin[ours]
        mass = symmetric(pin.crba(model, data, q_pin))
        np.testing.assert_allclose(theirs(space.mass_matrix(q)), mass, **tol)
        np.testing.assert_allclose(theirs(space.bias_forces(q, v)), pin.nonLinearEffects(
            model, data, q_pin, v_pin) + damping @ v_pin, **tol)
        np.testing.assert_allclose(theirs(space.inverse_dynamics(q, v, a)), pin.rnea(
            model, data, q_pin, v_pin, a_pin) + damping @ v_pin, **tol)
        applied = tau_pin - damping @ v_pin  # the joint forces Pinocchio's aba sees
        np.testing.assert_allclose(theirs(space.forward_dynamics(q, v, tau)),
                                   pin.aba(model, data, q_pin, v_pin, applied), **tol)
        pin.computeABADerivatives(model, data, q_pin, v_pin, applied)
        da_dq, da_dv, da_dtau = map(theirs, space.forward_dynamics_derivatives(q, v, tau))
        minv = symmetric(data.Minv)
        # derivatives: M^-1 of the panda reaches ~1e3 (its fingers): rtol 1e-9
        np.testing.assert_allclose(da_dq, data.ddq_dq, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(da_dv, data.ddq_dv - minv @ damping, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(da_dtau, minv, rtol=1e-9, atol=1e-9)
        pin.computeRNEADerivatives(model, data, q_pin, v_pin, a_pin)
        dtau_dq, dtau_dv, dtau_da = map(theirs, space.inverse_dynamics_derivatives(q, v, a))
        np.testing.assert_allclose(dtau_dq, data.dtau_dq, **tol)
        np.testing.assert_allclose(dtau_dv, data.dtau_dv + damping, **tol)
        np.testing.assert_allclose(dtau_da, symmetric(data.M), **tol)


def test_functions_are_casadi_functions_with_named_arguments(robot):
    space, model, _ = robot
    rnea = space["inverse_dynamics"]
    assert isinstance(rnea, ca.Function)
    assert rnea.name_in() == ["t", "q", "v", "a"] and rnea.name_out() == ["tau"]
    # symbolic use: the CasADi function in an expression graph equals the NumPy call
    q = ca.MX.sym("q", space.nq)
    tau = rnea(0, q, ca.DM.zeros(space.nv), ca.DM.zeros(space.nv))
    gravity = ca.Function("gravity", [q], [tau])
    q0 = next(states(model))[0]
    # the same function evaluated two ways: round-off
    np.testing.assert_allclose(np.array(gravity(q0)).ravel(),
                               space.bias_forces(q0, np.zeros(space.nv)), rtol=0, atol=1e-12)


PENDULUM = """casmech: 1
name: pendulum
parameters: {m: 1.0, L: 0.5}
gravity: [0, 0, -9.81]
bodies:
  - {name: rod, mass: m, inertia: [1.0e-3, 1.0e-3, 1.0e-3], position: [L, 0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: rod, at: [0, 0, 0], axis: [0, 1, 0]}
"""


def test_a_compiled_model_after_set_gives_the_new_values():
    """A bob (inertia 1e-3) at L along x: M = I + m L^2; turning by q about +y lowers it
    (x towards -z), so gravity drives q with m g L cos(q) and the bias is its negative."""
    functions = casmech.compile(casmech.loads(PENDULUM))
    for m, length in ((1.0, 0.5), (2.0, 0.5), (2.0, 1.5)):
        space = casmech.joint_space(functions.set(m=m, L=length))
        assert space.coordinates == ("pivot.angle",) and space.velocities == ("pivot.angle_dot",)
        q = np.array([0.3])
        # closed forms of a rigid pendulum: round-off
        np.testing.assert_allclose(space.mass_matrix(q), [[1e-3 + m * length**2]], rtol=1e-12,
                                   atol=0)
        np.testing.assert_allclose(space.bias_forces(q, [0.0]),
                                   [-m * 9.81 * length * np.cos(0.3)], rtol=1e-12, atol=0)
    assert casmech.joint_space(functions) is casmech.joint_space(functions)  # built once


def test_a_closed_loop_is_a_usage_error():
    with pytest.raises(UsageError, match="needs a tree of joints"):
        casmech.joint_space(casmech.load(MODELS / "four_bar.yaml"))


def test_forward_dynamics_of_every_joint_type_matches_the_rp_formulation():
    """tests/helpers/joint_zoo.yaml: revolute, translational and cylindrical joints driven by
    functions of t, universal, planar, fixed, spherical joints and a free block on a bushing.
    The joint space's accelerations a(t, q, v, 0), carried to the bodies through its
    forward kinematics, equal the r-p formulation's (casmech.compile's mass_matrix,
    generalized_forces, phi_q, gamma: the saddle system M q'' + phi_q^T lam = Q,
    phi_q q'' = gamma), a second formulation of the same model."""
    model = casmech.load(ROOT / "tests" / "helpers" / "joint_zoo.yaml")
    space, functions = casmech.joint_space(model), casmech.compile(model)
    assert {name.split(".")[0] for name in space.coordinates} == {
        "r1", "cy3", "u4", "pl5", "s7", "cyc2", "block"}  # p2, rc1 driven, f6 fixed
    t, q_, v_, qdot_, a_ = (ca.SX.sym(n, k) for n, k in (
        ("t", 1), ("q", space.nq), ("v", space.nv), ("qdot", space.nq), ("a", space.nv)))
    bodies, rates = space["forward_kinematics"](t, q_, v_)
    # the bodies' accelerations, d/dt of their rates along (qdot, a)
    chain = ca.Function("chain", [t, q_, v_, qdot_, a_], [
        bodies, ca.jacobian(bodies, q_), ca.jacobian(bodies, t), rates,
        ca.jacobian(rates, t) + ca.jacobian(rates, q_) @ qdot_ + ca.jacobian(rates, v_) @ a_])
    rng = np.random.default_rng(1)
    for t0 in (0.0, 0.4):
        q = space.neutral + rng.uniform(-0.3, 0.3, space.nq)
        for k, name in enumerate(space.coordinates):
            if name.endswith(".e0"):  # the spherical joint's and the free block's quaternions
                q[k:k + 4] /= np.linalg.norm(q[k:k + 4])
        v = rng.uniform(-1, 1, space.nv)
        a = space.forward_dynamics(q, v, np.zeros(space.nv), t0)
        q_b, by_q, by_t, q_dot_b, _ = (np.array(x) for x in chain(
            t0, q, v, np.zeros(space.nq), a))
        qdot = np.linalg.lstsq(by_q, q_dot_b - by_t, rcond=None)[0]  # q's rates (exact)
        joint_space = np.array(chain(t0, q, v, qdot, a)[4]).ravel()
        q_b, q_dot_b = q_b.ravel(), q_dot_b.ravel()
        mass, phi_q = functions.matrix("mass_matrix", q_b), functions.matrix("phi_q", t0, q_b)
        rows = phi_q.shape[0]
        saddle = np.block([[mass, phi_q.T], [phi_q, np.zeros((rows, rows))]])
        rhs = np.concatenate([functions.vector("generalized_forces", t0, q_b, q_dot_b),
                              functions.vector("gamma", t0, q_b, q_dot_b)])
        rp = np.linalg.solve(saddle, rhs)[:mass.shape[0]]
        # two formulations in double precision, accelerations up to ~1e2: atol 1e-9
        np.testing.assert_allclose(joint_space, rp, rtol=1e-10, atol=1e-9)


def joint_mass_matrix(space, functions, q, t: float = 0.0) -> np.ndarray:
    """M of the joint space from the r-p formulation (casmech.compile's mass_matrix, M_rp of
    the bodies' r-p coordinates): the kinetic energy 1/2 q_dot_b^T M_rp q_dot_b with the
    bodies' rates q_dot_b = J v linear in v gives M = J^T M_rp J."""
    t_, q_, v_ = ca.SX.sym("t"), ca.SX.sym("q", space.nq), ca.SX.sym("v", space.nv)
    bodies, rates = space["forward_kinematics"](t_, q_, v_)
    kinematics = ca.Function("kinematics", [t_, q_], [bodies, ca.jacobian(rates, v_)])
    q_b, jac = (np.array(x) for x in kinematics(t, q))
    return jac.T @ functions.matrix("mass_matrix", q_b.ravel()) @ jac


def check_newton_euler_and_derivatives(space, functions, q, v, a, t: float = 0.0):
    """RNEA(q, v, a) = M (a - ABA(q, v, 0)), M from the r-p formulation; the derivatives of
    the forward dynamics (in t too, and from a given acceleration) equal CasADi's AD of the
    articulated-body algorithm."""
    zero = np.zeros(space.nv)
    mass = joint_mass_matrix(space, functions, q, t)
    tau = space.inverse_dynamics(q, v, a, t)
    expected = mass @ (a - space.forward_dynamics(q, v, zero, t))
    # two formulations, one double-precision product each; forces up to ~1e2: 1e-12 of the scale
    scale = np.max(np.abs(expected))
    np.testing.assert_allclose(tau, expected, rtol=1e-12, atol=1e-12 * scale)
    aba = space["forward_dynamics"]
    t_, q_, v_, tau_ = (ca.SX.sym(n, aba.size1_in(k)) for k, n in enumerate(aba.name_in()))
    acceleration = aba(t_, q_, v_, tau_)
    by_ad = ca.Function("aba_ad", [t_, q_, v_, tau_],
                        [ca.jacobian(acceleration, w) for w in (q_, v_, tau_)])
    # the same identity at a known acceleration (a symbol), and in t (drivers): what an ODE
    # Jacobian given its right-hand side's value would use
    known, a_ = ca.SX.sym("known", space.nv), ca.SX.sym("a", space.nv)
    inverse = space["inverse_dynamics"](t_, q_, v_, a_)
    at_known = ca.Function("at_known", [t_, q_, v_, known],
                           forward_derivatives(inverse, a_, known, [t_, q_, v_]))
    by_t = ca.Function("by_t", [t_, q_, v_, tau_], [ca.jacobian(acceleration, t_)])
    reference = np.array(by_t(t, q, v, tau))
    at_a = at_known(t, q, v, space.forward_dynamics(q, v, tau, t))
    # as below
    np.testing.assert_allclose(np.array(at_a[0]), reference, rtol=1e-9,
                               atol=1e-9 * max(1.0, np.max(np.abs(reference))))
    ours_all = space.forward_dynamics_derivatives(q, v, tau, t)
    for ours, known_a in zip(ours_all, at_a[1:], strict=True):
        # the same graph at an acceleration computed apart: round-off of a
        np.testing.assert_allclose(np.array(known_a), ours, rtol=1e-10,
                                   atol=1e-10 * max(1.0, np.max(np.abs(ours))))
    for ours, reference in zip(ours_all, by_ad(t, q, v, tau), strict=True):
        reference = np.array(reference)
        # an identity solved by Cholesky against AD of a recursion; entries up to ~1e3 (the
        # Panda's fingers' M^-1): 1e-9 of the scale
        np.testing.assert_allclose(ours, reference, rtol=1e-9,
                                   atol=1e-9 * max(1.0, np.max(np.abs(reference))))


def test_newton_euler_and_derivatives_on_robots(robot):
    space, model, loaded = robot
    functions = casmech.compile(loaded)
    for q, v, a, _ in states(model, 2):
        check_newton_euler_and_derivatives(space, functions, q, v, a)


def test_newton_euler_and_derivatives_of_every_joint_type():
    """The joint zoo: driven joints (t = 0.4), quaternion coordinates (nq > nv), a free
    block on a bushing, a spring-damper."""
    model = casmech.load(ROOT / "tests" / "helpers" / "joint_zoo.yaml")
    space, functions = casmech.joint_space(model), casmech.compile(model)
    rng = np.random.default_rng(36)
    for t0 in (0.0, 0.4):
        q = space.neutral + rng.uniform(-0.3, 0.3, space.nq)
        for k, name in enumerate(space.coordinates):
            if name.endswith(".e0"):
                q[k:k + 4] /= np.linalg.norm(q[k:k + 4])
        v, a = rng.uniform(-1, 1, (2, space.nv))
        check_newton_euler_and_derivatives(space, functions, q, v, a, t0)
