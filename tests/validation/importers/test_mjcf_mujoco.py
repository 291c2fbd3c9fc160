"""MJCF import against MuJoCo on the same files: models nobody here wrote (MuJoCo Menagerie's
UR5e arm and Cassie biped, kept in tests/data/menagerie/ with their licences;
dm_control's cheetah when dm_control is installed), simulated torque-free by both engines and
compared by the centres of mass of the bodies at t = 0.5 s; and the mass properties, poses and
actuator forces of a file written to exercise every form the importer reads."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import casmech
from casmech.importers.emit import identifier, to_yaml
from casmech.importers.mjcf import import_mjcf
from tests.helpers.importers import DATA
from tests.helpers.mujoco_reference import casmech_run, mujoco_model, mujoco_run

mujoco = pytest.importorskip("mujoco")

MENAGERIE = DATA / "menagerie"
T_END = 0.5
TOLERANCE = 1e-6  # [m] the brief's bar; both engines integrate to ~1e-10 here


def compare(path, h, keyframe=None, velocities=None):
    start_mj, end_mj, time_mj = mujoco_run(path, T_END, h, keyframe, velocities)
    start, end, time = casmech_run(path, T_END, keyframe, velocities=velocities or {})
    assert set(end) == set(end_mj)
    np.testing.assert_allclose(time, time_mj, rtol=0, atol=1e-9)  # the same instant
    moved = max(np.abs(end_mj[b] - start_mj[b]).max() for b in end)
    assert moved > 0.02  # the bodies do move (a wrong mass or axis shows at 1e-2)
    for body in end:
        # the same pose read from the file: roundoff only
        np.testing.assert_allclose(start[body], start_mj[body], rtol=0, atol=1e-12)
        # RK4 at h and IDAS/CVODES at rtol 1e-10 agree far below the 1e-6 m asked for
        np.testing.assert_allclose(end[body], end_mj[body], rtol=0, atol=TOLERANCE,
                                   err_msg=body)


def test_ur5e_arm_falls_from_its_home_keyframe_as_in_mujoco():
    """Menagerie's UR5e (6 hinges, nested default classes, joint damping 200 and 15 N m s)
    released from its `home` keyframe under gravity. Without the armature (not translated)
    the wrist's damping time constant is ~1e-5 s, so MuJoCo's RK4 needs h = 5e-6."""
    compare(MENAGERIE / "universal_robots_ur5e" / "ur5e.xml", 5e-6, keyframe="home")


@pytest.mark.slow
def test_cassie_with_four_connect_loops_matches_mujoco():
    """Menagerie's Cassie: a free pelvis, ball-jointed rods, four `connect` loops (closed by
    casmech's spherical joints, by MuJoCo's stiffened soft constraints), shin and heel springs
    of 1500 and 1250 N m/rad, hinges with `ref` in degrees; in free fall (no contact) with the
    hips started turning (~10 s for each engine)."""
    compare(MENAGERIE / "agility_cassie" / "cassie.xml", 1e-5, velocities={
        "left-hip-roll": 1.0, "left-hip-pitch": -2.0, "right-hip-yaw": 1.5,
        "right-hip-pitch": 2.5})


@pytest.mark.filterwarnings("ignore:compiler attribute 'settotalmass' is deprecated")
def test_dm_control_cheetah_matches_mujoco():
    """dm_control's cheetah (its pip package; skipped without it): `include`s, a planar root
    of two slides and a hinge (casmech's planar joint), masses from capsule geoms scaled by
    `settotalmass`, joint springs and dampers, angles in degrees; thighs started turning."""
    suite = pytest.importorskip("dm_control.suite")
    path = Path(suite.__file__).parent / "cheetah.xml"
    compare(path, 1e-5, velocities={"bthigh": 3.0, "fshin": -4.0})


FORMS = """<mujoco model="forms">
  <compiler angle="radian" eulerseq="ZYX"/>
  <default>
    <geom density="800"/>
    <default class="light"><geom density="300"/></default>
  </default>
  <worldbody>
    <body name="a" pos="0.1 0.2 1" quat="0.9 0.1 -0.3 0.2">
      <joint name="a" type="hinge" axis="1 2 3" pos="0 0 0.1"/>
      <geom type="box" size="0.1 0.2 0.05" pos="0.1 0 0" euler="0.3 -0.2 0.5"/>
      <geom type="capsule" fromto="0 0 0 0.3 0.1 -0.2" size="0.04" class="light"/>
      <body name="b" pos="0.3 0 0" axisangle="0 1 1 0.7">
        <joint name="b" type="slide" axis="0 0 1" ref="0.05"/>
        <geom type="cylinder" size="0.05 0.1" xyaxes="1 1 0 -1 1 0.3"/>
        <geom type="ellipsoid" size="0.05 0.08 0.1" pos="0 0.1 0" zaxis="1 1 1" mass="0.7"/>
        <body name="c" pos="0 0 0.2">
          <joint name="c" type="ball"/>
          <geom type="sphere" size="0.07" pos="0.05 0 0"/>
          <body name="welded" pos="0.1 0 0" euler="0.1 0.2 0.3">
            <inertial pos="0.02 0 0" quat="1 0.2 0 0" mass="0.3" diaginertia="0.001 0.002 0.0025"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <keyframe>
    <key name="moving" qpos="0.4 0.12 0.9 0.1 0.3 -0.2" qvel="1.5 -0.3 0.5 -1 2"/>
  </keyframe>
</mujoco>
"""


def test_mass_properties_and_poses_agree_with_mujoco(tmp_path):
    """Every orientation form, geoms' masses (box, capsule by fromto, cylinder, ellipsoid with
    a given mass, sphere) with densities from default classes, a welded body with a rotated
    inertial, a keyframe pose: each casmech body's mass, centre of mass, principal moments and
    axes are MuJoCo's (body_mass, xipos, body_inertia, ximat of the welded group)."""
    path = tmp_path / "forms.xml"
    path.write_text(FORMS)
    model = casmech.loads(to_yaml(import_mjcf(path, keyframe="moving")), file=f"{path}.yaml")
    reference = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(reference)
    mujoco.mj_resetDataKeyframe(reference, data, 0)
    mujoco.mj_forward(reference, data)
    for body in model.bodies:
        ids = [k for k in range(reference.nbody) if reference.body_weldid[k] ==
               reference.body(body.name).id]
        mass = reference.body_mass[ids]
        centre = mass @ data.xipos[ids] / mass.sum()
        tensor = np.zeros((3, 3))
        for i, k in enumerate(ids):
            frame, arm = data.ximat[k].reshape(3, 3), data.xipos[k] - centre
            tensor += frame @ np.diag(reference.body_inertia[k]) @ frame.T + mass[i] * (
                np.eye(3) * (arm @ arm) - np.outer(arm, arm))
        from casmech.schema.bodies import rotation_matrix

        axes = rotation_matrix(body.euler_parameters)
        # the same formulas and frames in another order: roundoff only
        np.testing.assert_allclose(body.mass, mass.sum(), rtol=1e-13, atol=0)
        np.testing.assert_allclose(body.position, centre, rtol=0, atol=1e-13)
        np.testing.assert_allclose(axes, data.xmat[ids[0]].reshape(3, 3), rtol=0, atol=1e-12)
        np.testing.assert_allclose(axes @ body.inertia @ axes.T, tensor, rtol=1e-10,
                                   atol=1e-16)
        omega = data.cvel[ids[0]][:3]  # MuJoCo's com-based spatial velocity: angular first
        np.testing.assert_allclose(body.angular_velocity, omega, rtol=0, atol=1e-12)


ACTUATED = """<mujoco model="actuated">
  <option><flag contact="disable"/></option>
  <worldbody>
    <body name="arm" pos="0 0 1">
      <joint name="shoulder" axis="0 1 0" damping="0.2"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05"/>
      <body name="slider" pos="0.5 0 0">
        <joint name="slide" type="slide" axis="1 0 0" stiffness="30" springref="0.1"/>
        <geom type="box" size="0.05 0.05 0.05"/>
        <body name="tip" pos="0.1 0 0">
          <joint name="wrist" axis="0 1 0"/>
          <geom type="sphere" size="0.04" pos="0.1 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="push" joint="shoulder" gear="3" ctrlrange="-1 1"/>
    <position name="servo" joint="slide" kp="200" kv="5" forcerange="-4 4"/>
    <velocity name="spin" joint="wrist" kv="0.3"/>
    <general name="extra" joint="shoulder" gainprm="2" biastype="affine" biasprm="0.1 -1 -0.5"/>
  </actuator>
  <keyframe><key name="k" qpos="0.3 0.02 -0.4" ctrl="0.7 0.15 2 -0.3"/></keyframe>
</mujoco>
"""


def test_actuators_and_springs_give_mujoco_s_motion(tmp_path):
    """motor, position (kp, kv, forcerange: the clamp is reached), velocity and general
    actuators, two on one joint, a slide spring with springref, a hinge damper, controls from
    a keyframe: the motion over 0.5 s is MuJoCo's (actuation on, RK4 at h = 1e-5)."""
    path = tmp_path / "actuated.xml"
    path.write_text(ACTUATED)
    model, data = mujoco_model(path, 1e-5, "k")
    model.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
    data.ctrl[:] = [0.7, 0.15, 2, -0.3]
    mujoco.mj_forward(model, data)
    clamped = []
    positions = []
    for _ in range(50):
        mujoco.mj_step(model, data, nstep=1000)
        clamped.append(abs(data.actuator_force[1]) >= 4 - 1e-12)
        positions.append(data.xipos[1:].copy())
    assert any(clamped) and not all(clamped)  # the servo's force limit is met, then left
    functions = casmech.compile(casmech.loads(to_yaml(import_mjcf(path, keyframe="k")),
                                              file=f"{path}.yaml"))
    result = casmech.analyze(functions, "dynamics", t_end=T_END, output_step=0.01, rtol=1e-11,
                             atol=1e-13)
    names, values = casmech.results_table(functions, result)
    for k, name in enumerate(("arm", "slider", "tip")):
        mine = values[1:, [names.index(f"{name}.{c}") for c in "xyz"]]
        # a kink where the clamp starts limits both integrators' accuracy: 1e-7 m
        np.testing.assert_allclose(mine, np.array(positions)[:, k], rtol=0, atol=1e-7,
                                   err_msg=identifier(name))


COMPOSITES = """<mujoco model="composites">
  <option><flag contact="disable"/></option>
  <default><geom density="1000"/></default>
  <worldbody>
    <body name="gimbal" pos="0 0 1">
      <joint name="hip_z" axis="0 0 1" pos="0 0 0.1"/>
      <joint name="hip_x" axis="1 0 0" pos="0 0 0.1"/>
      <joint name="hip_y" axis="0 1 0" pos="0 0 0.1"/>
      <geom type="box" size="0.05 0.08 0.1" pos="0.02 0 -0.05"/>
      <body name="cross" pos="0 0 -0.2">
        <joint name="ankle_y" axis="0 1 0"/>
        <joint name="ankle_x" axis="1 0 0"/>
        <geom type="box" size="0.12 0.04 0.03" pos="0.05 0.01 -0.02"/>
      </body>
    </body>
    <body name="sleeve" pos="1 0 1" euler="20 10 0">
      <joint name="turn" axis="0 0 1"/>
      <joint name="push" type="slide" axis="0 0 1"/>
      <geom type="box" size="0.1 0.05 0.2" pos="0.05 0 0"/>
    </body>
    <body name="sledge" pos="2 0 1">
      <joint name="along_x" type="slide" axis="1 0 0"/>
      <joint name="along_z" type="slide" axis="0 0 1"/>
      <joint name="pitch" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0.1" size="0.05"/>
      <body name="puck" pos="0.3 0 0.1">
        <joint name="puck_x" type="slide" axis="1 0 0"/>
        <joint name="puck_y" type="slide" axis="0 1 0"/>
        <geom type="sphere" size="0.05"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
MOVING = {"hip_z": 1.0, "hip_x": -0.7, "hip_y": 0.5, "ankle_y": 2.0, "ankle_x": -1.0,
          "turn": 3.0, "push": 0.4, "along_x": 0.3, "along_z": 1.0, "pitch": 2.0,
          "puck_x": -0.5, "puck_y": 0.8}


def test_several_joints_in_one_body_move_as_in_mujoco(tmp_path):
    """Bodies with several joints become the casmech joint they amount to: three hinges
    meeting in a point (spherical), two perpendicular hinges (universal), a hinge and a slide
    on one line (cylindrical), two slides and a normal hinge (planar), two slides (basic
    constraints): the motion from moving joints is MuJoCo's."""
    path = tmp_path / "composites.xml"
    path.write_text(COMPOSITES)
    model = casmech.loads(to_yaml(import_mjcf(path)), file=f"{path}.yaml")
    assert [j.type for j in model.joints] == ["spherical", "universal", "cylindrical",
                                             "planar", "dp1", "dp1", "dp1", "dp2"]
    compare(path, 1e-5, velocities=MOVING)


GIMBAL_URDF = """<robot name="gimbal">
  <link name="base"/>
  <joint name="hip_z" type="revolute"><parent link="base"/><child link="virtual_1"/>
    <origin xyz="0 0 1.1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="virtual_1"/>
  <joint name="hip_x" type="revolute"><parent link="virtual_1"/><child link="virtual_2"/>
    <axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <link name="virtual_2"><inertial><mass value="0"/><inertia ixx="0" iyy="0" izz="0"/></inertial>
  </link>
  <joint name="hip_y" type="continuous"><parent link="virtual_2"/><child link="thigh"/>
    <axis xyz="0 1 0"/></joint>
  <link name="thigh"><inertial><origin xyz="0.02 0 -0.15"/><mass value="3"/>
    <inertia ixx="0.02" iyy="0.025" izz="0.01" ixy="0.001"/></inertial></link>
</robot>
"""
GIMBAL_MJCF = """<mujoco model="gimbal">
  <compiler angle="radian"/>
  <worldbody>
    <body name="thigh" pos="0 0 1.1">
      <joint name="hip_z" axis="0 0 1"/><joint name="hip_x" axis="1 0 0"/>
      <joint name="hip_y" axis="0 1 0"/>
      <inertial pos="0.02 0 -0.15" mass="3" fullinertia="0.02 0.025 0.01 0.001 0 0"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_urdf_massless_gimbal_moves_as_mujoco_s_three_hinges(tmp_path):
    """A URDF hip of three revolute joints through two massless links (as example-robot-
    data's human.urdf) is imported as one spherical joint; MuJoCo refuses the massless links,
    so the reference is the same hip written in MJCF as three hinges in one body. Started
    turning about all three axes, the thigh's centre of mass follows MuJoCo's."""
    from casmech.importers.urdf import import_urdf

    urdf = tmp_path / "gimbal.urdf"
    urdf.write_text(GIMBAL_URDF)
    mjcf = tmp_path / "gimbal.xml"
    mjcf.write_text(GIMBAL_MJCF)
    rates = {"hip_z": 1.5, "hip_x": -2.0, "hip_y": 2.5}
    imported = import_urdf(urdf, velocities=rates)
    assert [item.data["type"] for item in imported.joints] == ["spherical"]
    assert imported.joints[0].data["name"] == "hip"
    model = casmech.loads(to_yaml(imported), file=f"{urdf}.yaml")
    functions = casmech.compile(model)
    result = casmech.analyze(functions, "dynamics", t_end=T_END, output_step=T_END, rtol=1e-10,
                             atol=1e-12)
    names, values = casmech.results_table(functions, result)
    mine = values[-1, [names.index(f"thigh.{c}") for c in "xyz"]]
    _, end, _ = mujoco_run(mjcf, T_END, 1e-5, velocities=rates)
    assert np.abs(end["thigh"] - values[0, [names.index(f"thigh.{c}") for c in "xyz"]]).max() \
        > 0.02  # it moves (0.15 m from the pivot)
    np.testing.assert_allclose(mine, end["thigh"], rtol=0, atol=TOLERANCE)  # as compare()


WELDED = """<mujoco model="welded">
  <compiler angle="radian"/>
  <option><flag contact="disable"/></option>
  <worldbody>
    <body name="left" pos="0 0 1">
      <joint name="left_hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.03"/>
    </body>
    <body name="right" pos="1 0 1">
      <joint name="right_hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 -0.5 0 0" size="0.03"/>
    </body>
    <body name="hand" pos="0.5 0 1" euler="0 0.3 0">
      <joint name="hand_ball" type="ball"/>
      <geom type="box" size="0.1 0.05 0.02" pos="0.05 0 0"/>
      <site name="hand_tip" pos="0 0 0"/>
    </body>
    <body name="rider" pos="0 0.5 1">
      <joint name="rider_slide" type="slide" axis="1 0 0"/>
      <geom type="sphere" size="0.05"/>
    </body>
  </worldbody>
  <equality>
    <connect body1="left" body2="right" anchor="0.5 0 0"/>
    <weld body1="hand" body2="left"/>
    <weld name="off" body1="rider" body2="world" active="false"/>
  </equality>
</mujoco>
"""


def test_connect_and_weld_loops_move_as_in_mujoco(tmp_path):
    """Two bars joined by a `connect` (a closed loop of one DOF left), a body welded to one
    of them by a `weld` (casmech's fixed joint at its pose), an inactive weld left out: the
    motion under gravity from a moving start is MuJoCo's with stiffened constraints."""
    path = tmp_path / "welded.xml"
    path.write_text(WELDED)
    imported = import_mjcf(path)
    assert [(i.data["name"], i.data["type"]) for i in imported.joints][-2:] == [
        ("connect1", "spherical"), ("weld2", "fixed")]
    assert any("inactive equality off" in line for line in imported.trailer)
    compare(path, 1e-5, velocities={"left_hinge": 2.0, "right_hinge": -2.0,
                                    "rider_slide": 0.5})
