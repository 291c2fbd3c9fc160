"""A tree's ODE as per-joint kernels called over the tree in an MX graph: the articulated-body
algorithm of formulations/articulated.py (the same spatial conventions, the same blockwise
elimination of joints whose motion subspace selects rows), with each body's work in three
small Functions per joint type, one per pass, that take the body's data (its constant
transform from the parent's reference frame and its spatial inertia in its own) as an input.

The kernels depend on the joint type alone, so they are built (and compiled: backends/
tree_kernels.py) once, whatever the model; a model's ODE is then the MX graph of three kernel
calls per body, which builds in a fraction of the unrolled SX's time and evaluates in the
kernels' compiled code. Gravity enters as the ground's spatial acceleration (-g: Featherstone
2008, section 5.3), so no pass needs the bodies' global poses; the accelerations of pass 3 are
then relative to a frame falling with gravity, and the joints' accelerations exact.

`supported` says which trees the mapped ODE covers: a tree (no cut joint), no coordinate a
driver prescribes, a numeric IR, and no applied force but gravity; any other tree takes the
unrolled build (formulations/joint_system.build).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cache

import casadi as ca
import numpy as np

from casmech.core import spatial
from casmech.elements.joint_types import MOTIONS
from casmech.formulations.articulated import eliminate, local_motion
from casmech.formulations.tree import Tree
from casmech.model.ir import GROUND_INDEX, ModelIR

PASSES = ("down", "up", "accelerate")  # the kernels of one joint type, in pass order
CONSTANTS = 48  # a body's data: E_t (9, by columns), r_t (3), its reference-frame inertia (36)


def kernel_name(kind: str, step: str) -> str:
    return f"tree_{step}_{kind}"


def terms(kind: str, theta, u, data):
    """(E, r, S, c_J, theta_dot, inertia) of a body from its joint's (theta, u) and its data."""
    e_t, r_t = ca.reshape(data[0:9], 3, 3), data[9:12]
    inertia = ca.reshape(data[12:48], 6, 6)
    _, translation, subspace, rate, theta_dot, matrix = local_motion(kind)(theta, u)
    return matrix.T @ e_t, r_t + e_t.T @ translation, subspace, rate, theta_dot, inertia


@cache
def kernels(kind: str) -> dict[str, ca.Function]:
    """The three kernels of a joint type (SX), by kernel_name:
    down: (theta, u, data, V_parent) -> (V, theta_dot);
    up: (theta, u, data, V, IA_children, pA_children) -> (IA and pA passed to the parent,
    solved = [U; D^-1; residual] by columns), IA_children / pA_children the sums of the
    children's;
    accelerate: (theta, u, data, V, a_parent, solved) -> (a, u_dot)."""
    motion = MOTIONS[kind]
    theta, u = ca.SX.sym("theta", motion.n_q), ca.SX.sym("u", motion.n_v)
    data = ca.SX.sym("data", CONSTANTS)
    v_parent, v, a_parent = (ca.SX.sym(n, 6) for n in ("v_parent", "v", "a_parent"))
    ia_children, pa_children = ca.SX.sym("ia_children", 6, 6), ca.SX.sym("pa_children", 6)
    n_v = motion.n_v
    solved = ca.SX.sym("solved", 6 * n_v + n_v * n_v + n_v)
    e, r, subspace, rate, theta_dot, inertia = terms(kind, theta, u, data)
    relative = subspace @ u
    c = rate + spatial.cross_motion(v, relative)

    down = ca.Function(kernel_name(kind, "down"), [theta, u, data, v_parent],
                       [spatial.motion(e, r, v_parent) + relative, theta_dot],
                       ["theta", "u", "data", "v_parent"], ["v", "theta_dot"])

    ia = inertia + ia_children
    pa = spatial.cross_force(v, inertia @ v) + pa_children
    if n_v:  # no joint force: tau = 0
        ia, pa, (u_mat, d_inv, residual) = eliminate(subspace, spatial.selection(subspace),
                                                      ia, pa, c, 0)
        packed = ca.vertcat(ca.vec(u_mat), ca.vec(d_inv), residual)
    else:
        pa, packed = pa + ia @ c, ca.SX(0, 1)
    up = ca.Function(kernel_name(kind, "up"),
                     [theta, u, data, v, ia_children, pa_children],
                     [spatial.transformed_inertia(e, r, ia), spatial.force_back(e, r, pa),
                      packed],
                     ["theta", "u", "data", "v", "ia_children", "pa_children"],
                     ["ia", "pa", "solved"])

    a = spatial.motion(e, r, a_parent) + c
    u_dot = ca.SX(0, 1)
    if n_v:
        u_mat = ca.reshape(solved[0:6 * n_v], 6, n_v)
        d_inv = ca.reshape(solved[6 * n_v:6 * n_v + n_v * n_v], n_v, n_v)
        u_dot = d_inv @ (solved[6 * n_v + n_v * n_v:] - u_mat.T @ a)
        a = a + subspace @ u_dot
    accelerate = ca.Function(kernel_name(kind, "accelerate"),
                             [theta, u, data, v, a_parent, solved], [a, u_dot],
                             ["theta", "u", "data", "v", "a_parent", "solved"], ["a", "u_dot"])
    return {f.name(): f for f in (down, up, accelerate)}


def supported(ir: ModelIR, tree: Tree) -> str | None:
    """None when the mapped ODE covers the model's tree, else why not (module docstring)."""
    if tree.cut:
        return "the model has loop closures or couplings (cut joints)"
    if any(j.prescribed for j in tree.joints):
        return "a driver prescribes a joint coordinate"
    if any(prim.f is not None for prim in ir.primitives):
        return "a joint's rows depend on time"
    if ir.forces or ir.motors or ir.limits:
        return "the model has force elements, motors or stops"
    if any(isinstance(v, ca.SX) for j in tree.joints for v in (*j.parent_frame, *j.child_frame)):
        return "the model is parametric"
    return None


def body_data(ir: ModelIR, tree: Tree) -> np.ndarray:
    """Every tree joint's data (tree order; CONSTANTS rows, one column per joint): the constant
    motion transform (E_t, r_t) from the parent's reference frame (ground: the global frame)
    to the joint's parent frame F_p, and the child's spatial inertia in its reference frame
    (the child frame F_c, origin at the joint point)."""
    reference = {j.child: j.child_frame for j in tree.joints}
    columns = np.empty((CONSTANTS, len(tree.joints)))
    for k, joint in enumerate(tree.joints):
        c_p, s_p = (np.asarray(v, float) for v in joint.parent_frame)
        if joint.parent == GROUND_INDEX:
            e_t, r_t = c_p.T, s_p
        else:
            c_ref, o_ref = (np.asarray(v, float) for v in reference[joint.parent])
            e_t, r_t = c_p.T @ c_ref, c_ref.T @ (s_p - o_ref)
        axes, origin = (np.asarray(v, float) for v in joint.child_frame)
        child = ir.bodies[joint.child]
        at_center = np.zeros((6, 6))
        at_center[:3, :3], at_center[3:, 3:] = child.inertia, child.mass * np.eye(3)
        x = _transform(axes, -axes.T @ origin)
        columns[:, k] = np.concatenate([e_t.ravel("F"), r_t, (x.T @ at_center @ x).ravel("F")])
    return columns


def _transform(e: np.ndarray, r: np.ndarray) -> np.ndarray:
    """spatial.transform in NumPy."""
    skew = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
    return np.block([[e, np.zeros((3, 3))], [-e @ skew, e]])


def kernel_of(functions: Mapping[str, ca.Function], kind: str, step: str,
              made=None) -> ca.Function:
    """A kernel by joint type and step: from `functions` (by kernel_name) where there, else
    made(kind) (default: kernels, the SX ones)."""
    name = kernel_name(kind, step)
    return functions[name] if name in functions else (made or kernels)(kind)[name]


class Passes:
    """The three passes of the articulated-body algorithm over a supported tree at the MX state
    x = [theta; u] (joint_system's layout), per tree joint: theta, u, the body's data, V,
    theta_dot, the acceleration a (relative to the ground's -g) and u_dot; `index`: body ->
    its tree joint."""

    def __init__(self, ir: ModelIR, tree: Tree, x: ca.MX,
                 functions: Mapping[str, ca.Function] | None = None):
        functions = functions or {}
        joints = tree.joints
        n = len(joints)
        n_q = [MOTIONS[j.type].n_q for j in joints]
        n_v = [MOTIONS[j.type].n_v for j in joints]
        pieces = ca.vertsplit(x, [0, *np.cumsum(n_q + n_v).tolist()])
        self.theta, self.u = pieces[:n], pieces[n:]
        columns = body_data(ir, tree)
        self.data = [ca.MX(ca.DM(columns[:, k])) for k in range(n)]
        self.index = {j.child: k for k, j in enumerate(joints)}
        zero6, zero66 = ca.MX(ca.DM.zeros(6, 1)), ca.MX(ca.DM.zeros(6, 6))

        def kernel(kind: str, step: str) -> ca.Function:
            return kernel_of(functions, kind, step)

        self.v, self.theta_dot = [None] * n, [None] * n
        for k, j in enumerate(joints):
            parent = zero6 if j.parent == GROUND_INDEX else self.v[self.index[j.parent]]
            self.v[k], self.theta_dot[k] = kernel(j.type, "down").call(
                [self.theta[k], self.u[k], self.data[k], parent])
        passed: list[list] = [[] for _ in joints]  # per joint, its children's (IA, pA)
        solved = [None] * n
        for k in reversed(range(n)):
            j = joints[k]
            ia, pa, solved[k] = kernel(j.type, "up").call(
                [self.theta[k], self.u[k], self.data[k], self.v[k],
                 total([ia for ia, _ in passed[k]], zero66),
                 total([pa for _, pa in passed[k]], zero6)])
            if j.parent != GROUND_INDEX:
                passed[self.index[j.parent]].append((ia, pa))
        falling = ca.MX(ca.DM(np.concatenate([np.zeros(3), -np.asarray(ir.gravity, float)])))
        self.a, self.u_dot = [None] * n, [None] * n
        for k, j in enumerate(joints):
            parent = falling if j.parent == GROUND_INDEX else self.a[self.index[j.parent]]
            self.a[k], self.u_dot[k] = kernel(j.type, "accelerate").call(
                [self.theta[k], self.u[k], self.data[k], self.v[k], parent, solved[k]])

    @property
    def ode(self) -> ca.MX:
        return ca.vertcat(ca.MX(0, 1), *self.theta_dot, *self.u_dot)


def tree_ode(ir: ModelIR, tree: Tree, functions: Mapping[str, ca.Function] | None = None
             ) -> ca.Function:
    """(t, x) -> ode of a supported tree (joint_system.build's joint_ode: x = [theta; u] in
    its layout), as the MX graph of the kernels `functions` (by kernel_name; default the SX
    ones) called per body (Passes): pass 1 root to leaves, pass 2 leaves to root (each body's
    IA and pA summed over its children), pass 3 root to leaves from the ground's
    acceleration -g."""
    n_x = sum(MOTIONS[j.type].n_q + MOTIONS[j.type].n_v for j in tree.joints)
    t, x = ca.MX.sym("t"), ca.MX.sym("x", n_x)
    return ca.Function("joint_ode", [t, x], [Passes(ir, tree, x, functions).ode], ["t", "x"],
                       ["ode"])


def total(terms: list, zero):
    """The sum of `terms` (none: zero)."""
    if not terms:
        return zero
    result = terms[0]
    for term in terms[1:]:
        result = result + term
    return result
