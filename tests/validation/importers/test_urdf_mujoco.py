"""URDF import against MuJoCo loading the same file: mass properties, pose, visuals, and the
joint-space trajectory of a 6-joint arm under gravity from a moving, non-reference pose."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

import casmech
from casmech.importers.emit import to_yaml
from casmech.importers.urdf import import_urdf
from casmech.schema.bodies import rotation_matrix
from tests.helpers.importers import DATA

mujoco = pytest.importorskip("mujoco")

ARM = DATA / "arm6.urdf"
BODIES = ("shoulder", "upper_arm", "forearm", "wrist", "slider", "hand")
# URDF joint -> (parent body, child body) in casmech (the camera and tool0 links are merged)
JOINTS = {"pan": ("ground", "shoulder"), "lift": ("shoulder", "upper_arm"),
          "elbow": ("upper_arm", "forearm"), "wrist_roll": ("forearm", "wrist"),
          "extend": ("wrist", "slider"), "twist": ("slider", "hand")}
Q0 = {"pan": 0.3, "lift": -0.5, "elbow": 0.8, "wrist_roll": 0.2, "extend": 0.03, "twist": -0.4}
V0 = {"pan": 0.5, "lift": -1.0, "elbow": 0.7, "wrist_roll": 2.0, "extend": 0.1, "twist": 1.5}
TIMES = np.round(np.arange(0.0, 1.0 + 1e-9, 0.05), 12)
H = 1e-4  # MuJoCo's RK4 step: its error (~h^4) is far below the comparison's tolerance


def mujoco_model(folder=None):
    """MuJoCo's model of the URDF: its defaults (fixed links fused, inertia from the file),
    contacts and joint limits off (casmech has neither), RK4. Given a folder, a copy of the
    URDF with MuJoCo's extension element <mujoco><compiler discardvisual="false"/> is loaded
    (MuJoCo drops visuals while parsing otherwise)."""
    path = ARM
    if folder is not None:
        path = folder / ARM.name
        path.write_text(ARM.read_text().replace(
            '<robot name="arm6">', '<robot name="arm6">\n  <mujoco><compiler '
            'discardvisual="false"/></mujoco>'))
    model = mujoco.MjModel.from_xml_path(str(path))
    model.opt.disableflags |= (mujoco.mjtDisableBit.mjDSBL_CONTACT
                               | mujoco.mjtDisableBit.mjDSBL_LIMIT)
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    model.opt.timestep = H
    data = mujoco.MjData(model)
    for name in Q0:
        data.qpos[model.joint(name).qposadr[0]] = Q0[name]
        data.qvel[model.joint(name).dofadr[0]] = V0[name]
    mujoco.mj_forward(model, data)
    return model, data


def casmech_model(**initial):
    """The imported model with its joints' stops (from <limit>) removed, as MuJoCo's limits
    are off here."""
    imported = import_urdf(ARM, **initial)
    for joint in imported.joints:
        joint.data.pop("limit", None)
    return casmech.loads(to_yaml(imported), file=str(ARM) + ".yaml")


def test_mass_properties_agree_with_mujoco():
    """Masses, centres of mass and principal moments of every body (MuJoCo fuses the fixed
    links as the importer does)."""
    model, data = mujoco_model()
    bodies = {b.name: b for b in casmech_model(positions=Q0).bodies}
    for name in BODIES:
        body = model.body(name)
        mine = bodies[name]
        # the same numbers combined in another order: roundoff only
        np.testing.assert_allclose(mine.mass, body.mass[0], rtol=1e-14, atol=0)
        np.testing.assert_allclose(mine.position, data.body(name).xipos, rtol=0, atol=1e-14)
        np.testing.assert_allclose(np.linalg.eigvalsh(mine.inertia), np.sort(body.inertia),
                                   rtol=1e-12, atol=1e-18)
        # body axes = the link frame's (MuJoCo's xmat)
        np.testing.assert_allclose(rotation_matrix(mine.euler_parameters),
                                   data.body(name).xmat.reshape(3, 3), rtol=0, atol=1e-14)


def test_visuals_are_placed_as_mujoco_places_them(tmp_path):
    """Each geometry item, placed by its body's pose, is where MuJoCo puts the visual geom
    (centre and axes) when it keeps visuals."""
    model, data = mujoco_model(tmp_path)
    placed = []
    for body in casmech_model(positions=Q0).bodies:
        frame = rotation_matrix(body.euler_parameters)
        for item in body.geometry:
            placed.append((item["type"], body.position + frame @ item["offset"],
                           frame @ rotation_matrix(item["euler_parameters"])))
    geoms = [k for k in range(model.ngeom) if model.geom_bodyid[k] != 0]  # the base is ground
    assert len(placed) == len(geoms) == 4
    for (kind, centre, axes), k in zip(placed, geoms, strict=True):
        assert mujoco.mjtGeom(model.geom_type[k]).name.lower().endswith(kind)
        # the same frames composed in another order: roundoff only
        np.testing.assert_allclose(centre, data.geom_xpos[k], rtol=0, atol=1e-14)
        if kind != "sphere":  # MuJoCo may turn a box or cylinder about its symmetry axes
            np.testing.assert_allclose(np.abs(axes.T @ data.geom_xmat[k].reshape(3, 3)),
                                       np.eye(3), rtol=0, atol=1e-12)


def _urdf_axes() -> dict[str, np.ndarray]:
    root = ET.parse(ARM).getroot()
    axes = {}
    for joint in root.iter("joint"):
        axis = joint.find("axis")
        if axis is not None:
            vector = np.array(axis.get("xyz").split(), float)
            axes[joint.get("name")] = vector / np.linalg.norm(vector)
    return axes


def joint_values(table, axes: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Joint angles and slides from the bodies' poses in casmech's results: the rotation of
    the child relative to the parent about the URDF axis (in the child frame), the slide of the
    child's centre of mass along it (in the parent frame); plus the initial values."""
    def pose(body):
        if body == "ground":
            return np.zeros((len(table), 3)), np.tile(np.eye(3), (len(table), 1, 1))
        p = np.column_stack([table[f"{body}.e{k}"] for k in range(4)])
        x = np.column_stack([table[f"{body}.{c}"] for c in "xyz"])
        return x, np.array([rotation_matrix(row) for row in p])

    values = {}
    for joint, (parent, child) in JOINTS.items():
        (xp, rp), (xc, rc) = pose(parent), pose(child)
        if joint == "extend":
            axis = rp[0].T @ rc[0] @ axes[joint]  # in the parent frame (constant)
            local = np.einsum("kji,kj->ki", rp, xc - xp)
            values[joint] = Q0[joint] + (local - local[0]) @ axis
        else:
            relative = np.einsum("ji,kjl->kil", rp[0].T @ rc[0], np.einsum("kji,kjl->kil", rp,
                                                                            rc))
            vee = np.stack([relative[:, 2, 1] - relative[:, 1, 2],
                            relative[:, 0, 2] - relative[:, 2, 0],
                            relative[:, 1, 0] - relative[:, 0, 1]], axis=1) / 2
            cosine = (np.trace(relative, axis1=1, axis2=2) - 1) / 2
            values[joint] = Q0[joint] + np.arctan2(vee @ axes[joint], cosine)
    return values


class Results:
    def __init__(self, names, values):
        self.names, self.values = list(names), np.asarray(values)

    def __getitem__(self, name):
        return self.values[:, self.names.index(name)]

    def __len__(self):
        return len(self.values)


def test_trajectory_agrees_with_mujoco():
    """casmech (IDAS/CVODES at rtol 1e-10) and MuJoCo (RK4, h = 1e-4) on the same URDF from the
    same moving pose: joint values and centres of mass over 1 s."""
    functions = casmech.compile(casmech_model(positions=Q0, velocities=V0))
    result = casmech.analyze(functions, "dynamics", t_end=1.0, output_step=0.05, rtol=1e-10,
                             atol=1e-12)
    table = Results(*casmech.results_table(functions, result))
    np.testing.assert_allclose(table["t"], TIMES, rtol=0, atol=1e-12)
    model, data = mujoco_model()
    joints = {name: [] for name in JOINTS}
    centres = {name: [] for name in BODIES}
    steps = int(round((TIMES[1] - TIMES[0]) / H))
    for _ in TIMES:
        for name in JOINTS:
            joints[name].append(data.qpos[model.joint(name).qposadr[0]])
        for name in BODIES:
            centres[name].append(data.body(name).xipos.copy())
        mujoco.mj_step(model, data, nstep=steps)
    mine = joint_values(table, _urdf_axes())
    assert np.ptp(joints["pan"]) > 1 and np.ptp(joints["extend"]) > 0.5  # it does move
    for name in JOINTS:
        difference = np.array(mine[name]) - np.array(joints[name])
        if name != "extend":  # angles: equal modulo 2 pi
            difference = np.angle(np.exp(1j * difference))
        # both integrate to ~1e-10; 1e-7 leaves room for the growth of errors over a second of
        # a fast, coupled motion (a wrong inertia convention or axis differs by > 1e-2)
        np.testing.assert_allclose(difference, 0, rtol=0, atol=1e-7, err_msg=name)
    for name in BODIES:
        mine = np.column_stack([table[f"{name}.{c}"] for c in "xyz"])
        np.testing.assert_allclose(mine, np.array(centres[name]), rtol=0, atol=1e-7,
                                   err_msg=name)  # as above
