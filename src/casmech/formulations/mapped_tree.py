"""A tree's ODE as per-joint kernels called over the tree in an MX graph: the articulated-body
algorithm of formulations/articulated.py (the same spatial conventions, the same blockwise
elimination of joints whose motion subspace selects rows), with each body's work in three
small Functions per joint type, one per pass, that take the body's data (its constant
transform from the parent's reference frame and its spatial inertia in its own) as an input.

The kernels depend on the joint type alone, so they are built (and compiled: backends/
tree_kernels.py) once, whatever the model; a model's ODE is then the MX graph of three kernel
calls per body, which builds in a fraction of the unrolled SX's time and evaluates in the
kernels' compiled code. A run of BLOCK same-type joints along a chain is one call of block
kernels (the single-joint ones composed), as the machine's cost per call, not the kernels'
arithmetic, is most of an evaluation. Gravity enters as the ground's spatial acceleration
(-g: Featherstone 2008, section 5.3), so no pass needs the bodies' global poses; the
accelerations of pass 3 are then relative to a frame falling with gravity, and the joints'
accelerations exact.

`supported` says which trees the mapped ODE covers: a tree (no cut joint), no coordinate a
driver prescribes, a numeric IR, and no applied force but gravity; any other tree takes the
unrolled build (formulations/joint_system.build).
"""

from __future__ import annotations

from collections import Counter
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
BLOCK = 4  # the joints of a chain one call of a block kernel covers (block_kernels)


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


def block_name(kind: str, step: str, size: int) -> str:
    return kernel_name(kind, f"{step}_x{size}")


@cache
def block_kernels(kind: str, size: int = BLOCK) -> dict[str, ca.Function]:
    """The three kernels of `size` consecutive joints of a joint type along a chain (each
    joint's child the next one's parent, with no other child), by block_name: the
    single-joint kernels composed in SX, with the joints' theta, u, data, V (by joint,
    stacked) and solved stacked, and IA_children / pA_children those of the last child;
    down -> (V, theta_dot) of every joint, up -> (IA and pA of the first, solved of every
    joint), accelerate -> (a, u_dot) of every joint."""
    single = kernels(kind)
    motion = MOTIONS[kind]
    n_q, n_v = motion.n_q, motion.n_v
    n_s = 6 * n_v + n_v * n_v + n_v
    theta, u = ca.SX.sym("theta", n_q * size), ca.SX.sym("u", n_v * size)
    data, v = ca.SX.sym("data", CONSTANTS * size), ca.SX.sym("v", 6 * size)
    solved = ca.SX.sym("solved", n_s * size)
    v_parent, a_parent = ca.SX.sym("v_parent", 6), ca.SX.sym("a_parent", 6)
    ia_children, pa_children = ca.SX.sym("ia_children", 6, 6), ca.SX.sym("pa_children", 6)

    def joint(i: int) -> list:
        """(theta, u, data, V) of the block's joint i."""
        return [theta[i * n_q:(i + 1) * n_q], u[i * n_v:(i + 1) * n_v],
                data[i * CONSTANTS:(i + 1) * CONSTANTS], v[6 * i:6 * i + 6]]

    outputs, velocity = [], v_parent
    for i in range(size):
        velocity, theta_dot = single[kernel_name(kind, "down")](*joint(i)[:3], velocity)
        outputs.append((velocity, theta_dot))
    down = ca.Function(block_name(kind, "down", size), [theta, u, data, v_parent],
                       [ca.vertcat(*(o[0] for o in outputs)),
                        ca.vertcat(*(o[1] for o in outputs))],
                       ["theta", "u", "data", "v_parent"], ["v", "theta_dot"])
    ia, pa, packed = ia_children, pa_children, [None] * size
    for i in reversed(range(size)):
        ia, pa, packed[i] = single[kernel_name(kind, "up")](*joint(i), ia, pa)
    up = ca.Function(block_name(kind, "up", size),
                     [theta, u, data, v, ia_children, pa_children],
                     [ia, pa, ca.vertcat(*packed)],
                     ["theta", "u", "data", "v", "ia_children", "pa_children"],
                     ["ia", "pa", "solved"])
    outputs, a = [], a_parent
    for i in range(size):
        a, u_dot = single[kernel_name(kind, "accelerate")](
            *joint(i), a, solved[i * n_s:(i + 1) * n_s])
        outputs.append((a, u_dot))
    accelerate = ca.Function(block_name(kind, "accelerate", size),
                             [theta, u, data, v, a_parent, solved],
                             [ca.vertcat(*(o[0] for o in outputs)),
                              ca.vertcat(*(o[1] for o in outputs))],
                             ["theta", "u", "data", "v", "a_parent", "solved"], ["a", "u_dot"])
    return {f.name(): f for f in (down, up, accelerate)}


def segments(tree: Tree, size: int = BLOCK) -> list[tuple[int, int]]:
    """The tree joints in tree order as (first, count) runs: `size` consecutive joints of one
    type along a chain (each one's child the next one's parent and that child's only joint
    to a child) where there are, else one joint."""
    joints = tree.joints
    children = Counter(j.parent for j in joints)
    found, k = [], 0
    while k < len(joints):
        run = 1
        while run < size and k + run < len(joints) and joints[k + run].type == joints[k].type \
                and joints[k + run].parent == joints[k + run - 1].child \
                and children[joints[k + run - 1].child] == 1:
            run += 1
        count = size if run == size and size > 1 else 1
        found.append((k, count))
        k += count
    return found


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
    inertias: dict[bytes, np.ndarray] = {}  # by the child's frame and inertia (repeated bodies)
    for k, joint in enumerate(tree.joints):
        c_p, s_p = (np.asarray(v, float) for v in joint.parent_frame)
        if joint.parent == GROUND_INDEX:
            e_t, r_t = c_p.T, s_p
        else:
            c_ref, o_ref = (np.asarray(v, float) for v in reference[joint.parent])
            e_t, r_t = c_p.T @ c_ref, c_ref.T @ (s_p - o_ref)
        axes, origin = (np.asarray(v, float) for v in joint.child_frame)
        child = ir.bodies[joint.child]
        inertia, mass = np.asarray(child.inertia, float), float(child.mass)
        key = b"".join(a.tobytes() for a in (axes, origin, inertia, np.array(mass)))
        if key not in inertias:
            at_center = np.zeros((6, 6))
            at_center[:3, :3], at_center[3:, 3:] = inertia, mass * np.eye(3)
            x = _transform(axes, -axes.T @ origin)
            inertias[key] = (x.T @ at_center @ x).ravel("F")
        columns[:, k] = np.concatenate([e_t.ravel("F"), r_t, inertias[key]])
    return columns


def _transform(e: np.ndarray, r: np.ndarray) -> np.ndarray:
    """spatial.transform in NumPy."""
    skew = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
    return np.block([[e, np.zeros((3, 3))], [-e @ skew, e]])


def kernel_of(functions: Mapping[str, ca.Function], kind: str, step: str, count: int = 1,
              made=None, blocks=None) -> ca.Function:
    """A kernel by joint type and step, of one joint or of a block of `count`: from
    `functions` (by kernel_name, block_name) where there, else made(kind) (default: kernels,
    the SX ones) or blocks(kind, count) (default: block_kernels)."""
    if count == 1:
        name = kernel_name(kind, step)
        return functions[name] if name in functions else (made or kernels)(kind)[name]
    name = block_name(kind, step, count)
    return functions[name] if name in functions else \
        (blocks or block_kernels)(kind, count)[name]


class Passes:
    """The three passes of the articulated-body algorithm over a supported tree at the MX state
    x = [theta; u] (joint_system's layout), per tree joint: V and the acceleration a (relative
    to the ground's -g); `index`: body -> its tree joint; `ode`: the state's rates; `runs`:
    the segments with their inputs and outputs stacked. The joints are called in `segments`:
    one call of the block kernels per run of BLOCK joints of a chain, one of the single-joint
    kernels per other joint."""

    def __init__(self, ir: ModelIR, tree: Tree, x: ca.MX,
                 functions: Mapping[str, ca.Function] | None = None, size: int = BLOCK):
        functions = functions or {}
        joints = tree.joints
        n = len(joints)
        n_q = [MOTIONS[j.type].n_q for j in joints]
        n_v = [MOTIONS[j.type].n_v for j in joints]
        columns = body_data(ir, tree)
        self.index = {j.child: k for k, j in enumerate(joints)}
        runs = segments(tree, size)
        # each run's theta, u (one split of x) and data (one constant, split)
        firsts = [k for k, _ in runs] + [n]
        q_ends, v_ends = np.cumsum([0, *n_q]), np.cumsum([0, *n_v])
        split = ca.vertsplit(x, [*(int(q_ends[k]) for k in firsts),
                                 *(int(q_ends[n] + v_ends[k]) for k in firsts[1:])])
        theta, u = split[:len(runs)], split[len(runs):]
        data = ca.vertsplit(ca.MX(ca.DM(columns.ravel("F"))),
                            [CONSTANTS * k for k in firsts]) if n else []
        zero6, zero66 = ca.MX(ca.DM.zeros(6, 1)), ca.MX(ca.DM.zeros(6, 6))

        def kernel(r: int, step: str) -> ca.Function:
            k, count = runs[r]
            return kernel_of(functions, joints[k].type, step, count)

        self.v, velocities, theta_dot = [None] * n, [None] * len(runs), [None] * len(runs)
        for r, (k, count) in enumerate(runs):
            j = joints[k]
            parent = zero6 if j.parent == GROUND_INDEX else self.v[self.index[j.parent]]
            velocities[r], theta_dot[r] = kernel(r, "down").call(
                [theta[r], u[r], data[r], parent])
            self.v[k:k + count] = ca.vertsplit(velocities[r], 6) if count > 1 else \
                [velocities[r]]
        passed: list[list] = [[] for _ in joints]  # per joint, its children's (IA, pA)
        solved = [None] * len(runs)
        for r in reversed(range(len(runs))):
            k, count = runs[r]
            last = passed[k + count - 1]
            ia, pa, solved[r] = kernel(r, "up").call(
                [theta[r], u[r], data[r], velocities[r],
                 total([ia for ia, _ in last], zero66), total([pa for _, pa in last], zero6)])
            if joints[k].parent != GROUND_INDEX:
                passed[self.index[joints[k].parent]].append((ia, pa))
        falling = ca.MX(ca.DM(np.concatenate([np.zeros(3), -np.asarray(ir.gravity, float)])))
        self.a, u_dot, accelerations = [None] * n, [None] * len(runs), [None] * len(runs)
        for r, (k, count) in enumerate(runs):
            j = joints[k]
            parent = falling if j.parent == GROUND_INDEX else self.a[self.index[j.parent]]
            accelerations[r], u_dot[r] = kernel(r, "accelerate").call(
                [theta[r], u[r], data[r], velocities[r], parent, solved[r]])
            self.a[k:k + count] = ca.vertsplit(accelerations[r], 6) if count > 1 else \
                [accelerations[r]]
        self.ode = ca.vertcat(ca.MX(0, 1), *theta_dot, *u_dot)
        # per run (the results rows' block kernels read them): (first, count), theta, data,
        # V and a stacked
        self.runs = [(k, count, theta[r], data[r], velocities[r], accelerations[r])
                     for r, (k, count) in enumerate(runs)]


def tree_ode(ir: ModelIR, tree: Tree, functions: Mapping[str, ca.Function] | None = None
             ) -> ca.Function:
    """(t, x) -> ode of a supported tree (joint_system.build's joint_ode: x = [theta; u] in
    its layout), as the MX graph of the kernels `functions` (by kernel_name and block_name;
    default the SX ones) called per body or block (Passes): pass 1 root to leaves, pass 2
    leaves to root (each body's IA and pA summed over its children), pass 3 root to leaves
    from the ground's acceleration -g."""
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
