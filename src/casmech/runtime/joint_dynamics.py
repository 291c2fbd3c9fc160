"""Forward dynamics in joint coordinates (analysis.formulation: joint): SUNDIALS CVODES through
CasADi on the ODE of compiler.articulated, over the whole output grid in one call.

The initial state is the r-p one (assembly: the file's pose assembled, its velocities projected
onto the constraints), mapped to joint coordinates joint by joint (relative pose -> theta,
relative twist -> u by the joint's motion subspace), so both formulations start from the same
state. Each output row holds the r-p state the tree gives and the multipliers of every joint's
rows, from the Newton-Euler equations of each body: [Phi_r, Pi_bar]^T lam = F - M v_dot (the
r-omega form, whose rows are independent on a tree).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.compiler import euler
from casmech.compiler.articulated import JointSystem, build, local_motion
from casmech.compiler.functions import SystemFunctions
from casmech.compiler.ir import GROUND_INDEX
from casmech.compiler.joint_motions import MOTIONS
from casmech.compiler.tree import Tree, TreeJoint, spanning_tree
from casmech.errors import AnalysisError, FailureContext, UsageError
from casmech.runtime import assembly
from casmech.runtime.kinematics import output_times
from casmech.runtime.results import Result

MAX_STEPS = 500000  # CVODES steps per output interval before it gives up
CHUNK = 1000  # output intervals per CVODES call (a restart between calls)
METHODS = {"adams": {"linear_multistep_method": "adams",
                     "nonlinear_solver_iteration": "functional"},
           "bdf": {"linear_multistep_method": "bdf", "nonlinear_solver_iteration": "newton"}}


def joint_system(functions: SystemFunctions) -> JointSystem:
    """The bundle's joint system, built once per bundle."""
    if "joint_system" not in functions.derived:
        functions.derived["joint_system"] = build(functions.ir, require_tree(functions))
    return functions.derived["joint_system"]


def require_tree(functions: SystemFunctions) -> Tree:
    tree = spanning_tree(functions.ir)
    if not tree.is_tree:
        names = ", ".join(f"'{j.name}'" for j in tree.cut)
        raise UsageError(f"formulation 'joint' needs a tree of joints; these joints close "
                         f"loops or have no joint coordinates: {names} (use formulation rp)")
    return tree


class _Pose:
    """Global pose and velocity of a body (ground: fixed at the origin) from the r-p state."""

    def __init__(self, q, q_dot, n_bodies: int, k: int):
        if k == GROUND_INDEX:
            self.r, self.a = np.zeros(3), np.eye(3)
            self.r_dot, self.omega = np.zeros(3), np.zeros(3)
            return
        p = q[3 * n_bodies + 4 * k:3 * n_bodies + 4 * k + 4]
        p_dot = q_dot[3 * n_bodies + 4 * k:3 * n_bodies + 4 * k + 4]
        self.r, self.r_dot = q[3 * k:3 * k + 3], q_dot[3 * k:3 * k + 3]
        self.a = euler.numeric(euler.rotation, p)
        self.omega = 2 * euler.numeric(euler.g_matrix, p) @ p_dot  # body frame

    def origin(self, s):
        """Global position and velocity of the body-fixed point s."""
        return self.r + self.a @ s, self.r_dot + self.a @ np.cross(self.omega, s)


def joint_state(joint: TreeJoint, q, q_dot, n_bodies: int) -> tuple[np.ndarray, np.ndarray]:
    """(theta, u) of a tree joint at the r-p state."""
    parent, child = _Pose(q, q_dot, n_bodies, joint.parent), _Pose(q, q_dot, n_bodies,
                                                                   joint.child)
    (c_p, s_p), (c_c, s_c) = joint.parent_frame, joint.child_frame
    o_p, o_p_dot = parent.origin(s_p)
    o_c, o_c_dot = child.origin(s_c)
    rotation = c_p.T @ parent.a.T @ child.a @ c_c
    gap = parent.a.T @ (o_c - o_p)
    theta = MOTIONS[joint.type].coordinates(rotation, c_p.T @ gap)
    omega = c_c.T @ (child.omega - child.a.T @ parent.a @ parent.omega)
    gap_dot = c_p.T @ (parent.a.T @ (o_c_dot - o_p_dot) - np.cross(parent.omega, gap))
    twist = np.concatenate([omega, rotation.T @ gap_dot])
    n_v = MOTIONS[joint.type].n_v
    subspace = np.array(ca.DM(
        local_motion(joint.type)(theta, np.zeros(n_v))[2]).full()).reshape(6, n_v)
    u = np.linalg.lstsq(subspace, twist, rcond=None)[0] if n_v else np.zeros(0)
    return theta, u


def initial_state(system: JointSystem, q, q_dot, n_bodies: int) -> np.ndarray:
    """x0 = [theta; u] of the free coordinates and velocities at the r-p state."""
    lay = system.layout
    x0 = np.zeros(lay.n_x)
    for k, joint in enumerate(system.tree.joints):
        theta, u = joint_state(joint, q, q_dot, n_bodies)
        x0[list(lay.theta[k])] = theta[list(lay.free_theta[k])]
        x0[list(lay.u[k])] = u[list(lay.free_u[k])]
    return x0


def quaternion_signs(system: JointSystem, t0: float, x0, q0, n_bodies: int) -> np.ndarray:
    """+1 or -1 per body, so the tree's Euler parameters continue the r-p state's."""
    q = np.array(system.motion(t0, x0, np.ones(n_bodies))[0].full()).ravel()  # noqa
    p_tree = q[3 * n_bodies:].reshape(n_bodies, 4)
    p_rp = q0[3 * n_bodies:].reshape(n_bodies, 4)
    return np.where(np.sum(p_tree * p_rp, axis=1) < 0, -1.0, 1.0)


def run_joint_dynamics(functions: SystemFunctions, t_end: float, step: float, rtol: float,
                       atol: float, t0: float = 0.0, progress=None,
                       method: str = "adams") -> Result:
    system = joint_system(functions)
    tree = system.tree
    nb = functions.n_bodies
    q0, q_dot0 = assembly.initial_state(functions, t0)
    x0 = initial_state(system, q0, q_dot0, nb)
    signs = quaternion_signs(system, t0, x0, q0, nb)
    times = output_times(t0, t_end, step)
    result = Result("dynamics", on_row=progress)
    options = {"reltol": rtol, "abstol": atol, "max_num_steps": MAX_STEPS,
               "disable_internal_warnings": True} | METHODS[method]
    problem = system.problem
    recorder = _Recorder(functions, system, signs)
    steps = 0
    try:
        recorder(result, times[:1], x0[:, None])
        k, x = 0, x0
        while k < len(times) - 1:
            chunk = times[k + 1:k + 1 + CHUNK]
            integrator = ca.integrator("joint", "cvodes", problem, times[k], list(chunk),
                                       options)
            try:
                states = np.array(integrator(x0=x)["xf"].full())
            except RuntimeError as error:
                raise _failure(functions, times[k], chunk[-1], str(error)) from None
            steps += int(integrator.stats().get("nsteps", 0))
            recorder(result, chunk, states)
            k, x = k + len(chunk), states[:, -1]
    except AnalysisError as error:
        error.partial = result
        raise
    result.metadata.update(rtol=rtol, atol=atol, formulation="joint", integrator="cvodes",
                           method=method, steps=steps,
                           tree=[j.name or f"free '{functions.body_names[j.child]}'"
                                 for j in tree.joints],
                           cut_joints=[j.name for j in tree.cut])
    return result


def _failure(functions: SystemFunctions, t0: float, t1: float, why: str) -> AnalysisError:
    cause = f"CVODES failed between t = {t0:.6g} and {t1:.6g} ({why.splitlines()[-1]})"
    return AnalysisError(FailureContext(t0, cause, [], ""))


class _Recorder:
    """Appends results rows: the r-p state of the tree and every joint's multipliers."""

    def __init__(self, functions: SystemFunctions, system: JointSystem, signs):
        self.functions, self.system, self.signs = functions, system, signs

    def __call__(self, result: Result, times, states) -> None:
        n = len(times)
        rows = self.system.motion.map(n)(np.asarray(times)[None, :], states,
                                        np.repeat(self.signs[:, None], n, axis=1))
        q, q_dot, q_ddot, lam = (np.array(out.full()) for out in rows)
        for j, t in enumerate(times):
            result.append(t, q[:, j], q_dot[:, j], q_ddot[:, j], lam[:, j])
