"""casmech.joint_space (formulations.joint_space) against Pinocchio on robots imported from
example-robot-data's URDFs (both skipped without the packages): M(q) (crba), the bias forces
(nonLinearEffects plus the URDF's joint damping, which casmech's imported model applies),
forward and inverse dynamics (aba, rnea) and their derivatives (computeABADerivatives,
computeRNEADerivatives), at random states inside the joint limits; every tree joint type,
drivers and a free body against the r-p formulation of the same model."""

from __future__ import annotations

from importlib import metadata
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.errors import UsageError
from casmech.importers.emit import to_yaml
from casmech.importers.urdf import import_urdf

ROBOTS = {"ur5": "ur_description/urdf/ur5_robot.urdf",
          "panda": "panda_description/urdf/panda.urdf"}


def robots_folder() -> Path:
    try:
        distribution = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed (pip install example-robot-data)")
    return Path(distribution.locate_file("cmeel.prefix/share/example-robot-data"))


@pytest.fixture(params=sorted(ROBOTS))
def robot(request, tmp_path, monkeypatch):
    """(casmech JointSpace, pinocchio Model) of one robot."""
    pin = pytest.importorskip("pinocchio")
    folder = robots_folder()
    path = folder / "robots" / ROBOTS[request.param]
    monkeypatch.setenv("CASMECH_ALLOWED_DIRS", str(folder))  # its meshes
    out = tmp_path / f"{request.param}.yaml"
    model = import_urdf(path, output=out)
    # Pinocchio's URDF parser leaves <mimic> out: the fingers' coupler is left out here too
    model.joints = [joint for joint in model.joints if joint.data["type"] != "coupler"]
    out.write_text(to_yaml(model))
    space = casmech.joint_space(casmech.load(out))
    return space, pin.buildModelFromUrdf(str(path))


def states(model, count: int = 3):
    """Random (q, v, a, tau) with q inside the limits (casmech's imported stops act outside)."""
    rng = np.random.default_rng(34)
    low, high = model.lowerPositionLimit, model.upperPositionLimit
    for _ in range(count):
        yield (low + (high - low) * rng.uniform(0.1, 0.9, model.nq),
               *rng.uniform(-2, 2, (3, model.nv)))


def symmetric(upper: np.ndarray) -> np.ndarray:
    return np.triu(upper) + np.triu(upper, 1).T  # Pinocchio fills M's upper triangle


def test_joint_space_matches_pinocchio(robot):
    import pinocchio as pin

    space, model = robot
    data = model.createData()
    assert space.nq == model.nq and space.nv == model.nv
    assert list(space.joints) == [model.names[k] for k in range(1, model.njoints)]
    damping = np.diag(model.damping)
    # two recursive algorithms in double precision on entries up to ~50: atol 1e-10
    tol = {"rtol": 1e-10, "atol": 1e-10}
    for q, v, a, tau in states(model):
        mass = symmetric(pin.crba(model, data, q))
        np.testing.assert_allclose(space.mass_matrix(q), mass, **tol)
        np.testing.assert_allclose(space.bias_forces(q, v),
                                   pin.nonLinearEffects(model, data, q, v) + damping @ v, **tol)
        np.testing.assert_allclose(space.inverse_dynamics(q, v, a),
                                   pin.rnea(model, data, q, v, a) + damping @ v, **tol)
        applied = tau - damping @ v  # the joint forces Pinocchio's aba sees
        np.testing.assert_allclose(space.forward_dynamics(q, v, tau),
                                   pin.aba(model, data, q, v, applied), **tol)
        pin.computeABADerivatives(model, data, q, v, applied)
        da_dq, da_dv, da_dtau = space.forward_dynamics_derivatives(q, v, tau)
        minv = symmetric(data.Minv)
        # derivatives: M^-1 of the panda reaches ~1e3 (its fingers): rtol 1e-9
        np.testing.assert_allclose(da_dq, data.ddq_dq, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(da_dv, data.ddq_dv - minv @ damping, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(da_dtau, minv, rtol=1e-9, atol=1e-9)
        pin.computeRNEADerivatives(model, data, q, v, a)
        dtau_dq, dtau_dv, dtau_da = space.inverse_dynamics_derivatives(q, v, a)
        np.testing.assert_allclose(dtau_dq, data.dtau_dq, **tol)
        np.testing.assert_allclose(dtau_dv, data.dtau_dv + damping, **tol)
        np.testing.assert_allclose(dtau_da, symmetric(data.M), **tol)


def test_functions_are_casadi_functions_with_named_arguments(robot):
    space, model = robot
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
        casmech.joint_space(casmech.load(Path(__file__).parents[2] / "models/four_bar.yaml"))


def test_forward_dynamics_of_every_joint_type_matches_the_rp_formulation():
    """tests/runtime/joint_zoo.yaml: revolute, translational and cylindrical joints driven by
    functions of t, universal, planar, fixed, spherical joints and a free block on a bushing.
    The joint space's accelerations a(t, q, v, 0), carried to the bodies through its
    forward kinematics, equal the r-p formulation's (casmech.compile's mass_matrix,
    generalized_forces, phi_q, gamma: the saddle system M q'' + phi_q^T lam = Q,
    phi_q q'' = gamma), a second formulation of the same model."""
    model = casmech.load(Path(__file__).parents[1] / "runtime" / "joint_zoo.yaml")
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
