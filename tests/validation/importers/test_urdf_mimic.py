"""URDF <mimic> imported as a coupler: the relation q_B = m q_A + o between the joints' values
(from a posed import too), and the Panda of example-robot-data against MuJoCo loading the same
URDF, whose parser writes its mimic as a joint equality."""

from __future__ import annotations

import re
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest

import casmech
from casmech.importers.emit import to_yaml
from casmech.importers.urdf import import_urdf
from tests.conftest import Table

TWO_HINGES = """<?xml version="1.0"?>
<robot name="pair">
  <link name="base"/>
  <joint name="a" type="revolute">
    <parent link="base"/><child link="wheel_a"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <link name="wheel_a"><inertial><mass value="1"/>
    <inertia ixx="0.1" iyy="0.1" izz="0.2" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="b" type="revolute">
    <parent link="base"/><child link="wheel_b"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/>
    <mimic joint="a" multiplier="%s" offset="%s"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <link name="wheel_b"><inertial><mass value="1"/>
    <inertia ixx="0.2" iyy="0.2" izz="0.3" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>
"""


@pytest.mark.parametrize("positions", [{}, {"a": 0.2, "b": -0.1}])
def test_a_mimic_holds_between_the_urdf_joint_values(tmp_path, positions):
    """b = -0.5 a + 0.3 in URDF values, whatever pose the import starts from: with `a` driven
    the kinematics puts b there (casmech's coordinates are measured from the imported pose)."""
    path = tmp_path / "pair.urdf"
    path.write_text(TWO_HINGES % (-0.5, 0.3))
    imported = import_urdf(path, positions=positions)
    coupler = imported.joints[-1]
    assert coupler.data["type"] == "coupler" and coupler.data["joints"] == ["b", "a"]
    assert coupler.data["coefficients"] == [1.0, 0.5]  # [1, -multiplier]
    a0, b0 = positions.get("a", 0.0), positions.get("b", 0.0)
    imported.joints[0].data["driver"] = {"angle": "0.4 * sin(t)"}
    for joint in imported.joints:
        joint.data.pop("limit", None)
    model = casmech.loads(to_yaml(imported), file=str(path) + ".yaml")
    functions = casmech.compile(model)
    table = Table(*casmech.results_table(functions, casmech.analyze(
        functions, "kinematics", t_end=1.0, output_step=0.25)))
    a = a0 + table["a.angle"]
    # assembled to the position tolerance
    np.testing.assert_allclose(b0 + table["b.angle"], -0.5 * a + 0.3, rtol=0, atol=1e-10)


def test_a_mimic_of_a_joint_merged_away_is_a_warning(tmp_path):
    """wheel_a without mass: its joint is locked and merged, so the mimic has no joint to
    couple to and is said so (b is still imported)."""
    path = tmp_path / "pair.urdf"
    path.write_text((TWO_HINGES % (1, 0)).replace('<mass value="1"/>\n    <inertia ixx="0.1" '
                                                  'iyy="0.1" izz="0.2"', '<mass value="0"/>\n'
                                                  '    <inertia ixx="0" iyy="0" izz="0"'))
    imported = import_urdf(path)
    assert [j.data["type"] for j in imported.joints] == ["revolute"]
    assert any("mimic not translated: 'a' is not a joint of the model" in w.format()
               for w in imported.warnings)


mujoco = pytest.importorskip("mujoco")
H = 1e-4  # MuJoCo's RK4 step
TIMES = np.round(np.arange(0.0, 1.0 + 1e-9, 0.1), 12)


def panda() -> Path:
    try:
        distribution = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed (pip install example-robot-data)")
    return Path(distribution.locate_file(
        "cmeel.prefix/share/example-robot-data/robots/panda_description/urdf/panda.urdf"))


def mujoco_run(path: Path) -> tuple:
    """MuJoCo's model of the URDF (meshes replaced by boxes: visuals only), contacts, joint
    limits and friction loss off (casmech has none here), the mimic's equality as stiff as
    MuJoCo allows at this step (time constant 2 h), RK4; qpos at TIMES."""
    text = re.sub(r'<mesh filename="[^"]*"[^/]*/>', '<box size="0.01 0.01 0.01"/>',
                  path.read_text())
    model = mujoco.MjModel.from_xml_string(text)
    assert model.neq == 1 and model.eq_type[0] == mujoco.mjtEq.mjEQ_JOINT
    model.opt.disableflags |= (mujoco.mjtDisableBit.mjDSBL_CONTACT
                               | mujoco.mjtDisableBit.mjDSBL_LIMIT)
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    model.opt.timestep = H
    model.dof_frictionloss[:] = 0
    model.eq_solref[:] = [2 * H, 1.0]
    data = mujoco.MjData(model)
    states = [data.qpos.copy()]
    for _ in TIMES[1:]:
        for _ in range(round(0.1 / H)):
            mujoco.mj_step(model, data)
        states.append(data.qpos.copy())
    return model, np.array(states)


def test_the_panda_fingers_stay_coupled_and_the_arm_moves_as_in_mujoco(monkeypatch):
    """The Panda falling under gravity for 1 s from its reference pose, limits off: the mimic
    coupler keeps the fingers together (to the DAE's constraint tolerance) and every joint
    follows MuJoCo with its mimic equality on (uncoupled, the fingers drifted metres apart)."""
    path = panda()
    monkeypatch.setenv("CASMECH_ALLOWED_DIRS", str(path.parents[1] / "meshes"))
    imported = import_urdf(path)
    for joint in imported.joints:
        joint.data.pop("limit", None)
    model = casmech.loads(to_yaml(imported), file=str(path) + ".yaml")
    functions = casmech.compile(model)
    table = Table(*casmech.results_table(functions, casmech.analyze(
        functions, "dynamics", t_end=1.0, output_step=0.1, rtol=1e-10, atol=1e-12)))
    fingers = [table[f"panda_finger_joint{k}.displacement"] for k in (1, 2)]
    assert np.abs(fingers[0] - fingers[1]).max() < 1e-9
    reference, states = mujoco_run(path)
    for k in range(reference.njnt):
        name = reference.joint(k).name
        theirs = states[:, reference.joint(k).qposadr[0]]
        if name.startswith("panda_finger"):
            # MuJoCo's soft equality (2 h) and RK4 against the exact coupler: 1e-6 m
            np.testing.assert_allclose(table[f"{name}.displacement"], theirs, rtol=0,
                                       atol=2e-6, err_msg=name)
        else:  # casmech's angle is in (-pi, pi]; MuJoCo's qpos is not wrapped
            gap = np.angle(np.exp(1j * (table[f"{name}.angle"] - theirs)))
            # arm angles to 4e-6 rad in the run this was written against: 2e-5
            np.testing.assert_allclose(gap, 0.0, rtol=0, atol=2e-5, err_msg=name)
