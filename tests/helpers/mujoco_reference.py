"""MuJoCo as the second engine of the MJCF importer's tests: the same file simulated by MuJoCo
and by casmech, torque-free, and the centres of mass of the bodies compared.

MuJoCo's model is the file as MuJoCo compiles it, less what casmech does not translate (said in
docs/import.md): mesh geoms are removed (their files are not kept with the test data; every
moving body of the compared models has an <inertial>, so they carry no mass), contacts, joint
limits and actuators are disabled, armature and frictionloss set to zero and so are the
stiffness and damping of balls, free joints and bodies with several joints, `joint` equalities
deactivated; the remaining (connect, weld) equality constraints are stiffened (time constant
2 h, impedance 0.9999) so that MuJoCo's soft constraints approach casmech's exact joints. RK4
at a small step h: its error (~h^4) is far below the comparison's tolerance.
"""

from __future__ import annotations

import numpy as np

import casmech
from casmech.importers.emit import identifier, to_yaml
from casmech.importers.mjcf import import_mjcf


def mujoco_model(path, h: float, keyframe: str | None = None, velocities=None):
    import mujoco

    spec = mujoco.MjSpec.from_file(str(path))
    for geom in list(spec.geoms):
        if geom.type == mujoco.mjtGeom.mjGEOM_MESH:
            spec.delete(geom)
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    for material in list(spec.materials):  # textures are files too
        material.textures = [""] * len(material.textures)
    for texture in list(spec.textures):
        spec.delete(texture)
    model = spec.compile()
    model.opt.disableflags |= (mujoco.mjtDisableBit.mjDSBL_CONTACT
                               | mujoco.mjtDisableBit.mjDSBL_LIMIT
                               | mujoco.mjtDisableBit.mjDSBL_ACTUATION)
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    model.opt.timestep = h
    model.dof_armature[:] = 0
    model.dof_frictionloss[:] = 0
    for j in range(model.njnt):  # passive terms of balls, free joints and multi-joint bodies
        body = model.jnt_bodyid[j]
        kinds = (int(mujoco.mjtJoint.mjJNT_BALL), int(mujoco.mjtJoint.mjJNT_FREE))
        if model.jnt_type[j] in kinds or model.body_jntnum[body] > 1:
            size = {int(mujoco.mjtJoint.mjJNT_BALL): 3, int(mujoco.mjtJoint.mjJNT_FREE): 6}
            dofs = model.jnt_dofadr[j] + np.arange(size.get(int(model.jnt_type[j]), 1))
            model.dof_damping[dofs] = 0
            model.jnt_stiffness[j] = 0
    for k in range(model.neq):
        if model.eq_type[k] not in (int(mujoco.mjtEq.mjEQ_CONNECT), int(mujoco.mjtEq.mjEQ_WELD)):
            model.eq_active0[k] = 0
    model.eq_solref[:] = (2 * h, 1.0)
    model.eq_solimp[:] = (0.9999, 0.9999, 0.001, 0.5, 2)
    data = mujoco.MjData(model)
    if keyframe is not None:
        mujoco.mj_resetDataKeyframe(model, data, model.key(keyframe).id)
        data.ctrl[:] = 0
    for name, value in (velocities or {}).items():
        data.qvel[model.joint(name).dofadr[0]] = value
    mujoco.mj_forward(model, data)
    return model, data


def centres(model, data) -> dict[str, np.ndarray]:
    """The centre of mass of each group of welded bodies (a casmech body), by the casmech name
    of its head (the body with the joints)."""
    import mujoco

    found = {}
    for weld in sorted(set(model.body_weldid[1:]) - {0}):
        members = [b for b in range(model.nbody) if model.body_weldid[b] == weld]
        mass = model.body_mass[members]
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, weld)
        found[identifier(name or f"body{weld}")] = mass @ data.xipos[members] / mass.sum()
    return found


def mujoco_run(path, t_end: float, h: float, keyframe: str | None = None, velocities=None):
    import mujoco

    model, data = mujoco_model(path, h, keyframe, velocities)
    start = centres(model, data)
    mujoco.mj_step(model, data, nstep=int(round(t_end / h)))
    return start, centres(model, data), data.time


def torque_free(imported):
    """The imported model without its motors and contact elements (MuJoCo's actuation and
    contacts are disabled too)."""
    for item in imported.joints:
        item.data.pop("motor", None)
    imported.forces = [f for f in imported.forces if not f.data["type"].endswith("_plane")]
    imported.parameters = []
    return imported


def casmech_run(path, t_end: float, keyframe: str | None = None, rtol: float = 1e-10,
                **options):
    imported = torque_free(import_mjcf(path, keyframe=keyframe, **options))
    model = casmech.loads(to_yaml(imported), file=f"{path}.yaml")
    functions = casmech.compile(model)
    result = casmech.analyze(functions, "dynamics", t_end=t_end, output_step=t_end, rtol=rtol,
                             atol=rtol * 1e-2)
    names, values = casmech.results_table(functions, result)
    table = dict(zip(names, np.asarray(values).T, strict=True))
    bodies = [b.name for b in model.bodies]
    return ({b: np.array([table[f"{b}.{c}"][0] for c in "xyz"]) for b in bodies},
            {b: np.array([table[f"{b}.{c}"][-1] for c in "xyz"]) for b in bodies},
            table["t"][-1])
