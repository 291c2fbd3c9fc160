"""Exudyn: the benchmark systems as rigid bodies in redundant coordinates (node type Euler
parameters, Exudyn's default for CreateRigidBody) with ObjectJointSpherical / revolute joints,
integrated by Exudyn's default implicit solver (generalized-alpha, fixed step h, spectral radius
0.9, modified Newton). The accuracy knob is h; the Newton tolerances are tightened with it
(NEWTON_* below) so that they do not cap the accuracy of small steps.

The four-bar's loop is closed at C by a generic joint that constrains only the global x and y
components of the relative position (constrainedAxes [1,1,0,0,0,0]): with four revolutes a closed
planar loop carries 3 redundant constraints and Exudyn's Jacobian is singular (its own
fourBarMechanism3D example does the same)."""

from __future__ import annotations

import os
import time

import numpy as np
from systems import OUTPUT_STEP, T_CHECK, T_END, System, rotation_z


def _exudyn():
    import exudyn  # EXUDYN_MODULE=fast in the environment selects exudynCPPfast

    return exudyn


class Runner:
    tool = "exudyn"

    def __init__(self, system: System):
        exu = _exudyn()
        from exudyn.itemInterface import SensorBody
        from exudyn.utilities import RigidBodyInertia

        self.exu = exu
        self.system = system
        start = time.perf_counter()
        self.container = exu.SystemContainer()
        mbs = self.container.AddSystem()
        ground = mbs.CreateGround()
        bodies = {"ground": ground}
        self.sensors = []
        for bar in system.bars:
            inertia = RigidBodyInertia(mass=bar.mass, inertiaTensor=np.diag(bar.inertia),
                                       com=[0.0, 0.0, 0.0], inertiaTensorAtCOM=True)
            body = mbs.CreateRigidBody(inertia=inertia, referencePosition=list(bar.cm),
                                       referenceRotationMatrix=rotation_z(bar.angle),
                                       gravity=list(system.gravity), show=False)
            bodies[bar.name] = body
            for local in ([0.0, 0.0, 0.0], [0.5 * bar.length, 0.0, 0.0]):
                self.sensors.append(mbs.AddSensor(SensorBody(
                    bodyNumber=body, localPosition=local, storeInternal=True, writeToFile=False,
                    outputVariableType=exu.OutputVariableType.Position)))
        for joint in system.joints:
            items = [bodies[joint.parent], bodies[joint.child]]
            if joint.kind == "spherical":
                mbs.CreateSphericalJoint(itemNumbers=items, position=list(joint.at), show=False)
            elif joint.kind == "revolute":
                mbs.CreateRevoluteJoint(itemNumbers=items, position=list(joint.at),
                                        axis=list(joint.axis), show=False)
            elif joint.kind == "pin_xy":
                mbs.CreateGenericJoint(itemNumbers=items, position=list(joint.at),
                                       constrainedAxes=[1, 1, 0, 0, 0, 0], show=False)
            else:
                raise ValueError(joint.kind)
        mbs.Assemble()
        self.mbs = mbs
        self.build_time = {"build": time.perf_counter() - start}
        self.module = exu.__name__ + (" (fast)" if os.environ.get("EXUDYN_MODULE") else "")

    def settings(self, setting: dict, t_end: float = T_END):
        exu = self.exu
        s = exu.SimulationSettings()
        h = setting["h"]
        ti = s.timeIntegration
        ti.endTime = t_end
        ti.numberOfSteps = int(round(t_end / h))
        ti.verboseMode = 0
        newton_tol = setting.get("newton_rtol", NEWTON_RTOL)
        ti.newton.relativeTolerance = newton_tol
        ti.newton.absoluteTolerance = newton_tol * 1e-2
        s.solution.file.write = False
        s.solution.sensors.writePeriod = max(OUTPUT_STEP, h)
        # dense LU for the smallest systems, sparse LU above (measured faster from 8 bars on)
        small = len(self.system.bars) <= SMALL_SYSTEM
        s.linearSolver.solverType = (exu.LinearSolverType.EXUdense if small
                                     else exu.LinearSolverType.EigenSparse)
        s.displayStatistics = False
        s.displayComputationTime = False
        return s

    def run(self, setting: dict, t_end: float = T_END) -> dict:
        """setting: {"h": step size}; wall time of the simulation to t_end, points at T_CHECK."""
        settings = self.settings(setting, t_end)
        start, cpu_start = time.perf_counter(), time.process_time()
        ok = self.mbs.SolveDynamic(settings, solverType=self.exu.DynamicSolverType.GeneralizedAlpha)
        wall = time.perf_counter() - start
        cpu = time.process_time() - cpu_start
        if not ok:
            raise RuntimeError("Exudyn SolveDynamic failed")
        data = [self.mbs.GetSensorStoredData(s) for s in self.sensors]
        k = int(np.argmin(np.abs(data[0][:, 0] - T_CHECK)))
        if abs(data[0][k, 0] - T_CHECK) > 1e-9:
            raise RuntimeError(f"no sensor output at t = {T_CHECK}")
        final = float(data[0][-1, 0])
        if final < t_end - 1e-9:
            raise RuntimeError(f"Exudyn stopped at t = {final}")
        pts = np.array([d[k, 1:4] for d in data])
        return {"wall": wall, "cpu": cpu, "points": pts, "extra": {"final_time": final,
                                                       "module": self.module}}


NEWTON_RTOL = 1e-10  # Newton relative tolerance (default 1e-8); absolute = 1e-2 x this
SMALL_SYSTEM = 3  # bodies; up to this many Exudyn's dense solver was faster than EigenSparse
