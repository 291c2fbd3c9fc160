"""The joint formulation's state names, written once (elements.joint_types.state_names): every
tree joint type's states are named as its results columns where they are one (docs/format.md
"Joint states"), and hold those columns' values; the FMU's state variables and the joint
space's coordinates take the same names; an FMU's joint columns equal `casmech run`'s."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.elements.joint_types import MOTIONS, REGISTRY, attributes
from casmech.equations import readings
from casmech.fmu import description, outputs
from casmech.fmu.model import exported
from casmech.fmu.start import start
from casmech.fmu.system import build_system
from casmech.formulations.joint_space import joint_space
from casmech.formulations.registry import FORMULATIONS
from casmech.model.lower import lower

# every built-in joint type with a tree motion: its YAML keys beside body_i, body_j
KEYS = {
    "revolute": "at: [0, 0, 0], axis: [0.6, 0, 0.8]",
    "spherical": "at: [0, 0, 0]",
    "universal": "at: [0, 0, 0], axis_i: [1, 0, 0], axis_j: [0, 0.6, 0.8]",
    "cylindrical": "at: [0, 0, 0], axis: [0, 0.8, 0.6]",
    "translational": "at: [0, 0, 0], axis: [0, 0, 1]",
    "planar": "at: [0, 0, 0], axis: [0, 0, 1]",
    "fixed": "at: [0, 0, 0]",
}
# a spherical joint's velocities are in body_j's joint frame, its results columns' in
# body_i's: named apart (elements.joint_types.SPHERICAL_VELOCITIES)
APART = {"spherical": {"wx", "wy", "wz"}}


def _model(kind: str, folder):
    """A body on a joint of this kind to ground, off the joint point, moving."""
    path = folder / f"one_{kind}.yaml"
    path.write_text(f"""
casmech: 1
name: one_{kind}
gravity: [0, 0, -9.81]
bodies:
  - name: link
    mass: 2.0
    inertia: [0.1, 0.2, 0.3]
    position: [0.3, -0.2, -0.5]
    velocity: [0.4, -0.3, 0.2]
    angular_velocity: [0.5, 1.0, -0.7]
joints:
  - {{name: j, type: {kind}, body_i: ground, body_j: link, {KEYS[kind]}}}
analysis: {{type: dynamics, t_end: 0.1, output_step: 0.05}}
""")
    return casmech.load(path)


def test_every_tree_type_is_covered():
    """The table above names every registered joint type with a tree motion."""
    assert {name for name in MOTIONS if name != "free" and name in REGISTRY} == set(KEYS)


def _random_state(functions, rng) -> np.ndarray:
    """x with every quaternion block of unit norm."""
    names = FORMULATIONS["joint"].states(functions).differential
    x = rng.uniform(-1, 1, len(names))
    quaternion = [k for k, n in enumerate(names) if n.rsplit(".", 1)[1] in ("e0", "e1", "e2",
                                                                            "e3")]
    if quaternion:
        x[quaternion] /= np.linalg.norm(x[quaternion])
    return x


@pytest.mark.parametrize("kind", sorted(KEYS))
def test_states_are_the_results_columns(kind, tmp_path):
    """At random x, every state named as a results column holds that column's value (the
    columns from the r-p state the formulation's rows give, by equations.readings), and the
    states so named are the joint's state attributes (elements.joint_types.attributes) but
    those measured apart."""
    functions = casmech.compile(_model(kind, tmp_path), "interpreted")
    joint = FORMULATIONS["joint"]
    names = joint.states(functions).differential
    system = joint.system(functions)
    ir = functions.ir
    columns = readings.names(ir)
    function = readings.columns_function(ir)
    rng = np.random.default_rng(7)
    expected = {f"j.{a}" for a in attributes(kind)} - {f"j.{a}" for a in APART.get(kind, ())}
    assert {n for n in names if n in columns} == expected
    assert not {n for n in names if n in columns} ^ {c for c in columns if c in names}
    for _ in range(3):
        x = _random_state(functions, rng)
        p = np.ones(system.residual.size1_in(3))  # the quaternion signs: +1
        q, q_dot, _, _ = (np.array(v.full()).ravel()
                          for v in system.rows(0.2, x, np.zeros(system.n_z), p))
        values = np.array(function(0.2, q, q_dot, np.zeros_like(q), np.zeros((3, 1)),
                                   np.zeros((3, 1))).full()).ravel()
        for k, name in enumerate(names):
            if name in columns:
                # the same quantity by two formulas (tree coordinates, r-p): round-off
                np.testing.assert_allclose(x[k], values[columns.index(name)], rtol=0,
                                           atol=1e-12, err_msg=name)


def test_spherical_velocities_are_in_the_child_frame(tmp_path):
    """The spherical joint's wx_j.. are its results columns' wx.. turned into body_j's joint
    frame by the relative rotation e (so they are named apart)."""
    functions = casmech.compile(_model("spherical", tmp_path), "interpreted")
    system = FORMULATIONS["joint"].system(functions)
    ir = functions.ir
    columns = readings.names(ir)
    x = _random_state(functions, np.random.default_rng(3))
    q, q_dot, _, _ = (np.array(v.full()).ravel()
                      for v in system.rows(0.0, x, np.zeros(0), np.ones(1)))
    values = np.array(readings.columns_function(ir)(0.0, q, q_dot, np.zeros_like(q),
                                                    np.zeros((3, 1)),
                                                    np.zeros((3, 1))).full()).ravel()
    e0, e1, e2, e3 = x[:4]
    rotation = np.array([  # A(e), Haug's (6.3.11)
        [e0**2 + e1**2 - 0.5, e1 * e2 - e0 * e3, e1 * e3 + e0 * e2],
        [e1 * e2 + e0 * e3, e0**2 + e2**2 - 0.5, e2 * e3 - e0 * e1],
        [e1 * e3 - e0 * e2, e2 * e3 + e0 * e1, e0**2 + e3**2 - 0.5]]) * 2
    w = values[[columns.index(f"j.w{axis}") for axis in "xyz"]]
    # one rotation of the same vector: round-off
    np.testing.assert_allclose(x[4:7], rotation.T @ w, rtol=0, atol=1e-12)
    assert abs(np.linalg.norm(x[4:7] - w)) > 1e-3  # the frames differ at this state


@pytest.mark.parametrize("kind", sorted(KEYS))
def test_fmu_and_joint_space_take_the_names(kind, tmp_path, monkeypatch):
    """The FMU's state variables and the joint space's coordinates and velocities are the
    formulation's state names; at random states the FMU's joint columns (a state, or an
    output where no state has the name) equal `casmech run`'s (the interpreted results
    columns at the FMU's own r-p pose and rates of that state)."""
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path))
    model = _model(kind, tmp_path)
    functions = casmech.compile(model, "interpreted")
    names = FORMULATIONS["joint"].states(functions).differential
    space = joint_space(lower(model))
    assert space.coordinates + space.velocities == names
    view = exported(model)
    begin = start(model, view.inputs)
    every = outputs.names(functions)
    system = build_system(view, begin, list(range(len(every))))
    assert system.state_names == names
    if kind == "spherical":  # the FMU's unit of the child-frame angular velocities
        assert [description.state_unit(n) for n in names[4:]] == ["rad/s"] * 3
    call = system.functions
    jd = call["cm_data"](ca.DM(0, 1))
    ir = functions.ir
    columns = readings.names(ir)
    joint_columns = [f"j.{a}" for a in attributes(kind)]
    rng = np.random.default_rng(11)
    for _ in range(3):
        x = _random_state(functions, rng)
        y = np.array(call["cm_outputs"](0.2, x, jd).full()).ravel()
        fmu = dict(zip(system.state_names, x, strict=True)) | dict(
            zip(system.output_names, y, strict=True))
        assert set(joint_columns) <= set(fmu)  # none lost to a state of the same name
        q = call["cm_tree_pose"](0.2, x, jd)
        terms = call["cm_velocity_terms"](0.2, x, jd)
        u = x[system.n_theta:]
        q_dot = terms[0] @ u + terms[1]
        values = np.array(readings.columns_function(ir)(
            0.2, q, q_dot, ca.DM.zeros(q.shape), np.zeros((3, 1)),
            np.zeros((3, 1))).full()).ravel()
        for name in joint_columns:
            # the FMU's functions of its state against the r-p formulas: round-off
            np.testing.assert_allclose(fmu[name], values[columns.index(name)], rtol=0,
                                       atol=1e-12, err_msg=name)
