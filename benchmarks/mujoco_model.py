"""MuJoCo: the benchmark systems as MJCF kinematic trees in minimal coordinates (ball joints for
the chain, hinges for the four-bar), integrator RK4, fixed time step (the accuracy knob).

Each bar is a body whose frame sits at its proximal end with x along the bar; the joint is at
the body origin; the inertia is given explicitly (<inertial>), there are no geoms, so there is
no contact and nothing else adds mass. No joint damping, armature or limits.

The four-bar: crank and coupler hang from the world through hinges, the rocker through its own
hinge, and the loop is closed by an equality constraint <connect> at C. MuJoCo solves equality
constraints with its soft constraint solver, so the loop closure is not exact: the constraint
behaves like a stiff spring-damper set by solref/solimp (CONNECT_SOLREF, CONNECT_SOLIMP below,
as stiff as MuJoCo allows for the time step: solref time constant 2 x timestep with refsafe on,
the default, and the impedance 0.9999 at zero violation). Its error is measured like everyone
else's."""

from __future__ import annotations

import math
import time

import numpy as np
from systems import OUTPUT_STEP, T_CHECK, T_END, System, points

CONNECT_SOLIMP = "0.9999 0.9999 0.001 0.5 2"
SOLVER_TOLERANCE = 1e-12


def _f(x: float) -> str:
    return repr(float(x))


def _vec(v) -> str:
    return " ".join(_f(x) for x in v)


def mjcf(system: System, timestep: float, solref: str | None = None) -> str:
    """MJCF text; `solref` for the loop's connect (default: time constant 2 x timestep,
    damping ratio 1, the stiffest MuJoCo accepts with refsafe on)."""
    children: dict[str, list] = {}
    for joint in system.tree_joints:
        children.setdefault(joint.parent, []).append(joint)
    solref = solref or f"{_f(2 * timestep)} 1"

    def body(joint, parent_start, parent_angle, indent):
        bar = system.bar(joint.child)
        # body frame: origin at the bar's proximal end, x along the bar; relative to the parent
        c, s = math.cos(parent_angle), math.sin(parent_angle)
        dx, dy = bar.start[0] - parent_start[0], bar.start[1] - parent_start[1]
        pos = (c * dx + s * dy, -s * dx + c * dy, bar.start[2] - parent_start[2])
        rel = bar.angle - parent_angle
        pad = " " * indent
        out = [f'{pad}<body name="{bar.name}" pos="{_vec(pos)}" '
               f'quat="{_f(math.cos(rel / 2))} 0 0 {_f(math.sin(rel / 2))}">']
        if joint.kind == "spherical":
            out.append(f'{pad}  <joint name="{joint.name}" type="ball"/>')
        elif joint.kind == "revolute":
            axis = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]]) @ np.array(joint.axis)
            cr, sr = math.cos(rel), math.sin(rel)
            local = np.array([[cr, sr, 0], [-sr, cr, 0], [0, 0, 1]]) @ axis
            out.append(f'{pad}  <joint name="{joint.name}" type="hinge" axis="{_vec(local)}"/>')
        else:
            raise ValueError(joint.kind)
        out.append(f'{pad}  <inertial pos="{_f(bar.length / 2)} 0 0" mass="{_f(bar.mass)}" '
                   f'diaginertia="{_vec(bar.inertia)}"/>')
        for child in children.get(bar.name, []):
            out += body(child, bar.start, bar.angle, indent + 2)
        out.append(f"{pad}</body>")
        return out

    lines = [f'<mujoco model="{system.name}">',
             '  <compiler angle="radian" autolimits="true"/>',
             f'  <option timestep="{_f(timestep)}" integrator="RK4" '
             f'gravity="{_vec(system.gravity)}" tolerance="{_f(SOLVER_TOLERANCE)}" '
             'iterations="100">',
             '    <flag contact="disable"/>',
             "  </option>",
             "  <worldbody>"]
    for joint in children.get("ground", []):
        lines += body(joint, (0.0, 0.0, 0.0), 0.0, 4)
    lines.append("  </worldbody>")
    if system.loop_joints:
        lines.append("  <equality>")
        for joint in system.loop_joints:
            parent = system.bar(joint.parent)
            anchor = np.array(joint.at) - np.array(parent.start)
            c, s = math.cos(parent.angle), math.sin(parent.angle)
            local = (c * anchor[0] + s * anchor[1], -s * anchor[0] + c * anchor[1], anchor[2])
            lines.append(f'    <connect name="{joint.name}" body1="{joint.parent}" '
                         f'body2="{joint.child}" anchor="{_vec(local)}" '
                         f'solref="{solref}" solimp="{CONNECT_SOLIMP}"/>')
        lines.append("  </equality>")
    lines.append("</mujoco>")
    return "\n".join(lines) + "\n"


class Runner:
    tool = "mujoco"

    def __init__(self, system: System):
        import mujoco

        self.mujoco = mujoco
        self.system = system
        self.models: dict = {}
        self.build_time = {}

    def model(self, timestep: float, solref: str | None):
        key = (timestep, solref)
        if key not in self.models:
            start = time.perf_counter()
            model = self.mujoco.MjModel.from_xml_string(mjcf(self.system, timestep, solref))
            self.build_time = {"compile": time.perf_counter() - start}
            self.models[key] = (model, self.mujoco.MjData(model))
        return self.models[key]

    def run(self, setting: dict, t_end: float = T_END) -> dict:
        """setting: {"timestep": h, optional "solref": "..."}; wall time of the simulation to
        t_end (qpos recorded every OUTPUT_STEP), points at T_CHECK."""
        mujoco = self.mujoco
        h = setting["timestep"]
        model, data = self.model(h, setting.get("solref"))
        period = max(OUTPUT_STEP, h)
        per_output = int(round(period / h))
        n_outputs = int(round(t_end / period))
        check = int(round(T_CHECK / period))
        if abs(per_output * h - period) > 1e-12 * period or abs(check * period - T_CHECK) > 1e-12:
            raise ValueError(f"timestep {h} does not divide the output period and {T_CHECK} s")
        qpos = np.empty((n_outputs + 1, model.nq))
        start, cpu_start = time.perf_counter(), time.process_time()
        mujoco.mj_resetData(model, data)
        qpos[0] = data.qpos
        for k in range(1, n_outputs + 1):
            mujoco.mj_step(model, data, nstep=per_output)
            qpos[k] = data.qpos
        wall = time.perf_counter() - start
        cpu = time.process_time() - cpu_start
        final = float(data.time)
        # positions at T_CHECK from the recorded coordinates
        probe = mujoco.MjData(model)
        probe.qpos[:] = qpos[check]
        mujoco.mj_kinematics(model, probe)
        cms, rotations = [], []
        for bar in self.system.bars:
            b = model.body(bar.name).id
            rot = probe.xmat[b].reshape(3, 3)
            cms.append(probe.xpos[b] + rot @ np.array([bar.length / 2, 0.0, 0.0]))
            rotations.append(rot)
        pts = points(self.system, np.array(cms), np.array(rotations))
        extra = {"final_time": final}
        if self.system.loop_joints:
            mujoco.mj_forward(model, probe)
            extra["loop_violation"] = float(np.max(np.abs(probe.efc_pos[:probe.ne]), initial=0))
        return {"wall": wall, "cpu": cpu, "points": pts, "extra": extra}
