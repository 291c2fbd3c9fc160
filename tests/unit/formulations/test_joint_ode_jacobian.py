"""A tree's ODE Jacobian by the RNEA identity (formulations/joint_system.py,
JointSystem.identity_jacobian: d u'/d(t, x) = -M^-1 dRNEA/d(t, x) at the ODE's own value)
against CasADi's AD of the ODE itself (the articulated-body recursion, a second formulation),
on gallery trees and imported robots, and the integrator that uses it against the one that
uses forward sweeps of the ODE."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.formulations.joint_system import build
from casmech.formulations.tree import spanning_tree
from casmech.importers.emit import to_yaml
from casmech.importers.urdf import import_urdf
from tests.conftest import MODELS
from tests.unit.formulations.test_joint_system import ZOO, random_state
from tests.validation.formulations.test_joint_space import ROBOTS, robots_folder

RNG = np.random.default_rng(36)


def ad_jacobian(system) -> ca.Function:
    """(t, x) -> (d ode/dt, d ode/dx) by CasADi's AD of the ODE."""
    t, x = ca.SX.sym("t"), ca.SX.sym("x", system.layout.n_x)
    ode = system.dynamics(t, x)
    return ca.Function("reference", [t, x], [ca.jacobian(ode, t), ca.jacobian(ode, x)])


def assert_identity_is_the_ad_jacobian(system, count: int = 3) -> None:
    identity, reference = system.identity_jacobian(), ad_jacobian(system)
    assert system.jacobian is identity  # what the integrator receives (JointSystem.problem)
    for _ in range(count):
        t, x = RNG.uniform(0, 2), random_state(system)
        x[system.layout.n_theta:] = RNG.uniform(-2, 2, system.layout.n_x - system.layout.n_theta)
        for a, b in zip(identity(t, x, system.dynamics(t, x)), reference(t, x), strict=True):
            b = np.array(b)
            # two derivatives of the same dynamics, differing by the Cholesky solves' and the
            # recursions' roundoff: 1e-9 of the largest entry
            np.testing.assert_allclose(np.array(a), b, rtol=0, atol=1e-9 * np.max(np.abs(b)))


@pytest.mark.parametrize("path", [ZOO, *(MODELS / f"{name}.yaml" for name in (
    "flyball_governor", "quadruped_legs", "heavy_top", "bushing_mount", "chain_repeat",
    "cart_pole"))], ids=lambda p: p.stem)
def test_identity_jacobian_of_gallery_trees(path):
    """Drivers (d/dt of the flyball governor's, the legs' and the zoo's prescribed motions),
    force elements, a free body's quaternion."""
    functions = casmech.compile(casmech.load(path), "interpreted")
    assert_identity_is_the_ad_jacobian(build(functions.ir, spanning_tree(functions.ir)))


def robot_ir(name: str, tmp_path, monkeypatch):
    """The IR of a robot imported from example-robot-data (as
    tests/validation/formulations/test_joint_space.py)."""
    folder = robots_folder()
    monkeypatch.setenv("CASMECH_ALLOWED_DIRS", str(folder))  # its meshes
    out = tmp_path / f"{name}.yaml"
    model = import_urdf(folder / "robots" / ROBOTS[name], output=out)
    # the Panda's finger coupler would make a loop (its DAE keeps its own Jacobian)
    model.joints = [joint for joint in model.joints if joint.data["type"] != "coupler"]
    out.write_text(to_yaml(model))
    return casmech.compile(casmech.load(out), "interpreted").ir


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_identity_jacobian_of_imported_robots(name, tmp_path, monkeypatch):
    """With the importer's joint damping and limit stops (applied forces through the chain)."""
    ir = robot_ir(name, tmp_path, monkeypatch)
    assert_identity_is_the_ad_jacobian(build(ir, spanning_tree(ir)))


def test_bdf_run_with_the_identity_is_the_run_with_forward_sweeps(tmp_path, monkeypatch):
    """CVODES's BDF on the UR5 from a random state over 0.5 s, its Newton iterations on the
    identity's Jacobian or (identity_states=0) on forward sweeps of the ODE: one trajectory."""
    ir = robot_ir("ur5", tmp_path, monkeypatch)
    identity, sweeps = (build(ir, spanning_tree(ir), identity_states=n) for n in (200, 0))
    assert identity.identity_jacobian is not None and sweeps.identity_jacobian is None
    x0 = random_state(identity)
    finals = []
    for system in (identity, sweeps):
        problem = {k: v for k, v in system.problem.items() if k in ("t", "x", "ode")}
        integrator = ca.integrator("run", "cvodes", problem, 0, [0.25, 0.5],
                                   {"linear_multistep_method": "bdf", "reltol": 1e-10,
                                    "abstol": 1e-10})
        finals.append(np.array(integrator(x0=x0)["xf"]))
    # the same ODE, Newton iterations on equal Jacobians (to roundoff): the runs differ by
    # their step sequences' error, within the tolerance 1e-10 run's own error
    np.testing.assert_allclose(finals[0], finals[1], rtol=0, atol=1e-7)
