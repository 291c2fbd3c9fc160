"""The results rows of a mapped tree (formulations/mapped_tree.py) as kernels over the tree:
the r-p state, its rates and accelerations, every tree joint's row multipliers, and the
joints' relative poses, as joint_system.build gives them (JointSystem.motion and
relative_states), without the unrolled SX.

Per joint type, two kernels with the body's data as inputs: `pose` (root to leaves: a child's
global position, rotation matrix and Euler parameters from its parent's, as
articulated.kinematics composes them) and `wrench` (leaves to root: the wrench the joint exerts
on its child, the Newton-Euler balance of the child's subtree, articulated.joint_wrenches),
and the two composed over the blocks the ODE's passes call (block_kernels). The work of each
body that needs no recursion (its Euler-parameter rates, accelerations and its joint's wrench
at the CM) is one kernel mapped over all bodies, and the multipliers one mapped call per
structure of the joints' rows (joint_system.rows_inputs), over index tables.

The accelerations of mapped_tree's pass 3 are relative to a frame falling with gravity; the
bodies' accelerations add gravity back, while the wrench pass takes them as they are (the
inertia times the falling frame's acceleration is the gravity wrench the unrolled bias holds).
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from functools import cache

import casadi as ca
import numpy as np

from casmech.core import spatial
from casmech.core.quaternions import conjugate, from_matrix, product
from casmech.elements.joint_types import MOTIONS
from casmech.formulations import mapped_tree
from casmech.formulations.articulated import at_center, local_motion
from casmech.formulations.joint_system import rows_structure
from casmech.formulations.tree import Tree
from casmech.formulations.tree_steps import body_rates, relative_step, tree_multipliers
from casmech.model.ir import GROUND_INDEX, ModelIR

POSE_CONSTANTS = 32  # s_p (3), C_p (9), C_c (9), s_c (3), C_p's quaternion (4), C_c's (4)


@cache
def kernels(kind: str) -> dict[str, ca.Function]:
    """The pose and wrench kernels of a joint type (SX), by mapped_tree.kernel_name:
    pose: (theta, pose_data, r_parent, A_parent, p_parent) -> (r, A, p);
    wrench: (theta, data, V, a, children) -> (wrench on the child, the same in the parent's
    reference frame), in the child's reference frame; `children`: the sum of its children's
    second outputs."""
    motion = MOTIONS[kind]
    theta = ca.SX.sym("theta", motion.n_q)
    pose_data, data = ca.SX.sym("pose_data", POSE_CONSTANTS), ca.SX.sym("data",
                                                                         mapped_tree.CONSTANTS)
    r_p, a_p, p_p = ca.SX.sym("r_parent", 3), ca.SX.sym("A_parent", 3, 3), ca.SX.sym("p_parent",
                                                                                     4)
    s_p, s_c = pose_data[0:3], pose_data[21:24]
    c_p, c_c = ca.reshape(pose_data[3:12], 3, 3), ca.reshape(pose_data[12:21], 3, 3)
    q_cp, q_cc = pose_data[24:28], pose_data[28:32]
    rotation, translation, _, _, _, matrix = local_motion(kind)(theta, ca.SX.zeros(motion.n_v))
    a_k = a_p @ (c_p @ matrix @ c_c.T)
    r_k = r_p + a_p @ (s_p + c_p @ translation) - a_k @ s_c
    p_k = product(product(product(p_p, q_cp), rotation), conjugate(q_cc))
    pose = ca.Function(mapped_tree.kernel_name(kind, "pose"), [theta, pose_data, r_p, a_p, p_p],
                       [r_k, a_k, p_k], ["theta", "pose_data", "r_parent", "A_parent",
                                         "p_parent"], ["r", "A", "p"])

    u = ca.SX.zeros(motion.n_v)
    v, a, children = ca.SX.sym("v", 6), ca.SX.sym("a", 6), ca.SX.sym("children", 6)
    e, r, _, _, _, inertia = mapped_tree.terms(kind, theta, u, data)
    total = children + inertia @ a + spatial.cross_force(v, inertia @ v)
    wrench = ca.Function(mapped_tree.kernel_name(kind, "wrench"), [theta, data, v, a, children],
                         [total, spatial.force_back(e, r, total)],
                         ["theta", "data", "v", "a", "children"], ["wrench", "back"])
    return {f.name(): f for f in (pose, wrench)}


@cache
def block_kernels(kind: str, size: int = mapped_tree.BLOCK) -> dict[str, ca.Function]:
    """The pose and wrench kernels of `size` consecutive joints of a chain (mapped_tree.
    block_kernels' runs), by mapped_tree.block_name: the single-joint ones composed in SX,
    with the joints' theta, data, V, a stacked; pose -> (r, A side by side, p) of every joint
    from the first one's parent's; wrench -> (every joint's wrench on its child, stacked; the
    first one's back in its parent's frame), `children` those of the last joint's child."""
    single = kernels(kind)
    n_q = MOTIONS[kind].n_q
    theta = ca.SX.sym("theta", n_q * size)
    pose_data = ca.SX.sym("pose_data", POSE_CONSTANTS * size)
    data = ca.SX.sym("data", mapped_tree.CONSTANTS * size)
    v, a, children = ca.SX.sym("v", 6 * size), ca.SX.sym("a", 6 * size), ca.SX.sym("children", 6)
    r_p, a_p, p_p = ca.SX.sym("r_parent", 3), ca.SX.sym("A_parent", 3, 3), ca.SX.sym("p_parent",
                                                                                     4)

    def part(vector, width: int, i: int):
        return vector[i * width:(i + 1) * width]

    poses, parent = [], (r_p, a_p, p_p)
    for i in range(size):
        parent = single[mapped_tree.kernel_name(kind, "pose")](
            part(theta, n_q, i), part(pose_data, POSE_CONSTANTS, i), *parent)
        poses.append(parent)
    pose = ca.Function(mapped_tree.block_name(kind, "pose", size),
                       [theta, pose_data, r_p, a_p, p_p],
                       [ca.vertcat(*(x[0] for x in poses)), ca.horzcat(*(x[1] for x in poses)),
                        ca.vertcat(*(x[2] for x in poses))],
                       ["theta", "pose_data", "r_parent", "A_parent", "p_parent"],
                       ["r", "A", "p"])
    wrenches, back = [None] * size, children
    for i in reversed(range(size)):
        wrenches[i], back = single[mapped_tree.kernel_name(kind, "wrench")](
            part(theta, n_q, i), part(data, mapped_tree.CONSTANTS, i), part(v, 6, i),
            part(a, 6, i), back)
    wrench = ca.Function(mapped_tree.block_name(kind, "wrench", size),
                         [theta, data, v, a, children], [ca.vertcat(*wrenches), back],
                         ["theta", "data", "v", "a", "children"], ["wrench", "back"])
    return {f.name(): f for f in (pose, wrench)}


@cache
def body_rows() -> ca.Function:
    """(sign, p, A, V, a, wrench, C_c, s_c, g) -> (p sign, r_dot, p_dot, r_ddot, p_ddot, the
    wrench at the CM in body axes) of one body: V, a (relative to the falling frame) and the
    wrench in its reference frame F_c = (C_c, s_c) in body coordinates, g the gravity."""
    sign, p, rotation = ca.SX.sym("sign"), ca.SX.sym("p", 4), ca.SX.sym("A", 3, 3)
    v, a, w = ca.SX.sym("v", 6), ca.SX.sym("a", 6), ca.SX.sym("wrench", 6)
    axes, origin, gravity = ca.SX.sym("C_c", 3, 3), ca.SX.sym("s_c", 3), ca.SX.sym("g", 3)
    to_center = (axes, -axes.T @ origin)
    velocity = spatial.motion(*to_center, v)
    falling = ca.vertcat(ca.SX.zeros(3), (rotation @ axes).T @ gravity)
    acceleration = spatial.motion(*to_center, a + falling)
    signed, p_dot, r_ddot, p_ddot = body_rates.fn(sign, p, rotation, velocity, acceleration)
    (centred,) = at_center.fn(axes, origin, w)
    return ca.Function("tree_body_rows", [sign, p, rotation, v, a, w, axes, origin, gravity],
                       [signed, rotation @ velocity[3:6], p_dot, r_ddot, p_ddot, centred])


@cache
def multipliers(rows: int) -> ca.Function:
    """(B, A, wrench) -> a tree joint's row multipliers from its wrench on the child (CM,
    body axes): -B^T lam = (A w_force, w_torque), B the rows' r-omega Jacobian at the child,
    in the least-squares sense (joint_system.tree_multipliers)."""
    block, rotation, w = ca.SX.sym("B", rows, 6), ca.SX.sym("A", 3, 3), ca.SX.sym("w", 6)
    return ca.Function(f"tree_multipliers_{rows}", [block, rotation, w],
                       list(tree_multipliers.fn(block, rotation, w)))


def pose_data(tree: Tree) -> np.ndarray:
    """Every tree joint's pose data (POSE_CONSTANTS rows, one column per joint)."""
    columns = np.empty((POSE_CONSTANTS, len(tree.joints)))
    quaternions: dict[bytes, np.ndarray] = {}  # by matrix (the frames' axes repeat)

    def quaternion(matrix: np.ndarray) -> np.ndarray:
        key = matrix.tobytes()
        if key not in quaternions:
            quaternions[key] = from_matrix(matrix)
        return quaternions[key]

    for k, joint in enumerate(tree.joints):
        (c_p, s_p), (c_c, s_c) = ((np.asarray(m, float), np.asarray(o, float))
                                  for m, o in (joint.parent_frame, joint.child_frame))
        columns[:, k] = np.concatenate([s_p, c_p.ravel("F"), c_c.ravel("F"), s_c,
                                        quaternion(c_p), quaternion(c_c)])
    return columns


class Rows:
    """The results rows of a mapped tree at an MX state: the passes' outputs per tree joint
    (mapped_tree.Passes) composed with the pose and wrench kernels."""

    def __init__(self, ir: ModelIR, tree: Tree, passes: mapped_tree.Passes,
                 functions: Mapping[str, ca.Function]):
        self.ir, self.tree, self.passes = ir, tree, passes
        self.functions = functions

    def kernel(self, kind: str, step: str, count: int) -> ca.Function:
        """The pose or wrench kernel of one joint (count 1) or of a block of `count`."""
        return mapped_tree.kernel_of(self.functions, kind, step, count, kernels, block_kernels)

    def motion(self, signs) -> list:
        """(q, q_dot, q_ddot, lam) of the results row (joint_system.build's motion)."""
        ir, tree, passes = self.ir, self.tree, self.passes
        joints, nb = tree.joints, ir.n_bodies
        columns = pose_data(tree)
        # per run of the passes (one joint or a block), its pose data: one constant, split
        data = ca.vertsplit(ca.MX(ca.DM(columns.ravel("F"))),
                            [POSE_CONSTANTS * k for k, *_ in passes.runs] +
                            [POSE_CONSTANTS * len(joints)])
        index = passes.index
        r, a_rot, p = [None] * len(joints), [None] * len(joints), [None] * len(joints)
        ground = (ca.MX(ca.DM.zeros(3)), ca.MX(ca.DM.eye(3)), ca.MX(ca.DM([1, 0, 0, 0])))
        for run, (k, count, theta, _, _, _) in enumerate(passes.runs):
            j = joints[k]
            parent = ground if j.parent == GROUND_INDEX else (
                r[index[j.parent]], a_rot[index[j.parent]], p[index[j.parent]])
            outputs = self.kernel(j.type, "pose", count).call([theta, data[run], *parent])
            r[k:k + count], a_rot[k:k + count], p[k:k + count] = (
                (ca.vertsplit(outputs[0], 3), ca.horzsplit(outputs[1], 3),
                 ca.vertsplit(outputs[2], 4)) if count > 1 else ([x] for x in outputs))
        passed: list[list] = [[] for _ in joints]
        wrench = [None] * len(joints)
        zero6 = ca.MX(ca.DM.zeros(6, 1))
        for k, count, theta, body, v, a in reversed(passes.runs):
            j = joints[k]
            stacked, back = self.kernel(j.type, "wrench", count).call(
                [theta, body, v, a, mapped_tree.total(passed[k + count - 1], zero6)])
            wrench[k:k + count] = ca.vertsplit(stacked, 6) if count > 1 else [stacked]
            if j.parent != GROUND_INDEX:
                passed[index[j.parent]].append(back)
        order = [index[b] for b in range(nb)]  # body -> its tree joint

        def by_body(values: list):
            return ca.horzcat(*(values[k] for k in order))

        frames = [joints[k].child_frame for k in order]
        axes = ca.DM(np.hstack([np.asarray(f[0], float) for f in frames]))
        origins = ca.DM(np.column_stack([np.asarray(f[1], float) for f in frames]))
        rows = self.functions.get("tree_body_rows", body_rows())
        rotations = by_body(a_rot)
        signed, r_dot, p_dot, r_ddot, p_ddot, at_center = rows.map(nb).call(
            [ca.transpose(signs), by_body(p), rotations, by_body(passes.v), by_body(passes.a),
             by_body(wrench), axes, origins, ca.DM(np.asarray(ir.gravity, float))])
        positions = by_body(r)
        q = ca.vertcat(ca.vec(positions), ca.vec(signed))
        q_dot = ca.vertcat(ca.vec(r_dot), ca.vec(p_dot))
        q_ddot = ca.vertcat(ca.vec(r_ddot), ca.vec(p_ddot))
        lam = self._lam(positions, by_body(p), rotations, at_center)
        return [q, q_dot, q_ddot, lam]

    def _lam(self, positions, quaternions, rotations, at_center):
        """Every row's multiplier: each tree joint's from its wrench on the child, one mapped
        call per structure of the joints' rows and side of the child; the others zero."""
        ir, nb = self.ir, self.ir.n_bodies
        r_ext = ca.horzcat(positions, ca.DM.zeros(3, 1))  # ground: column nb
        p_ext = ca.horzcat(quaternions, ca.DM([1, 0, 0, 0]))
        groups: dict[tuple, list] = {}
        for joint in self.tree.joints:
            ir_joint = joint.joint
            if ir_joint is None:  # a floating body's free joint has no rows
                continue
            template, stacked, drivers = _rows_inputs(ir, ir_joint)
            side = joint.child == ir_joint.body_i
            groups.setdefault((template, side), []).append(
                (ir_joint, joint.child, stacked, drivers))
        lam = ca.MX.zeros(len(ir.row_info()), 1)
        for (template, side), members in groups.items():
            count = len(members)

            def column(k: int) -> list[int]:
                return [nb if k == GROUND_INDEX else k]

            cols_i = [c for m in members for c in column(m[0].body_i)]
            cols_j = [c for m in members for c in column(m[0].body_j)]
            children = [m[1] for m in members]
            stacked = ca.DM(np.column_stack([m[2] for m in members])) if members[0][2].size \
                else ca.DM(0, count)
            drivers = ca.DM(np.column_stack([m[3] for m in members])) if members[0][3].size \
                else ca.DM(0, count)
            template = self.functions.get(rows_name(template), template)
            _, block_i, block_j = template.map(count).call(
                [r_ext[:, cols_i], p_ext[:, cols_i], r_ext[:, cols_j], p_ext[:, cols_j],
                 stacked, drivers])
            block = block_i if side else block_j
            rows = len(members[0][0].rows)
            child_rotations = rotations[:, [3 * c + i for c in children for i in range(3)]]
            solve = multipliers(rows)
            values = self.functions.get(solve.name(), solve).map(count).call(
                [block, child_rotations, at_center[:, children]])[0]
            lam[[row for m in members for row in m[0].rows]] = ca.vec(values)
        return lam


MAX_ROWS = 6  # a tree joint's rows (its multipliers' kernels: 1 to MAX_ROWS)


def common() -> dict[str, ca.Function]:
    """The kernels of every tree whatever its joint types: the per-body rows and the
    multipliers of 1 to MAX_ROWS rows, by name."""
    return {f.name(): f for f in (body_rows(), *(multipliers(m)
                                                  for m in range(1, MAX_ROWS + 1)))}


def templates(ir: ModelIR, tree: Tree) -> dict[str, ca.Function]:
    """The rows' Functions (joint_system.rows_template) the tree's multipliers call, by
    rows_name."""
    found = {}
    for joint in tree.joints:
        if joint.joint is not None:
            template = _rows_inputs(ir, joint.joint)[0]
            found[rows_name(template)] = template
    return found


_NAMES: dict[int, tuple[ca.Function, str]] = {}


def rows_name(template: ca.Function) -> str:
    """A rows Function's name by its content, the name its compiled version has."""
    seen = _NAMES.get(id(template))
    if seen is None or seen[0] is not template:
        digest = hashlib.sha256(template.serialize().encode()).hexdigest()[:16]
        seen = _NAMES[id(template)] = (template, f"tree_rows_{digest}")
    return seen[1]


def _rows_inputs(ir: ModelIR, joint) -> tuple:
    """(joint_system.rows_template of a tree joint's rows, their vectors stacked, their
    driver values): what joint_system.rows_of passes it after the poses, for a numeric IR
    whose rows do not depend on time (mapped_tree.supported)."""
    template, vectors, prims = rows_structure(ir, joint)
    drivers = np.array([prim.offset for prim in prims], float)
    return template, np.concatenate([np.zeros(0), *(np.ravel(v) for v in vectors)]), drivers


def relative_states(tree: Tree, n_bodies: int) -> ca.Function:
    """(q, q_dot) -> (rotations 3 x 3n, gaps 3 x n, twists 6 x n): joint_system's
    relative_states, one mapped call of its step over the tree joints."""
    q, q_dot = ca.MX.sym("q", 7 * n_bodies), ca.MX.sym("q_dot", 7 * n_bodies)
    step = _relative_function()

    def columns(vector, rest: list[float]):
        """(positions, quaternions) of every body, ground's last."""
        positions = ca.reshape(vector[:3 * n_bodies], 3, n_bodies)
        quaternions = ca.reshape(vector[3 * n_bodies:], 4, n_bodies)
        return (ca.horzcat(positions, ca.DM.zeros(3, 1)),
                ca.horzcat(quaternions, ca.DM(rest)))

    (r, p), (r_dot, p_dot) = columns(q, [1, 0, 0, 0]), columns(q_dot, [0, 0, 0, 0])
    parents = [n_bodies if j.parent == GROUND_INDEX else j.parent for j in tree.joints]
    children = [j.child for j in tree.joints]
    sides = [[(np.asarray(m, float), np.asarray(o, float)) for m, o in
              (j.parent_frame for j in tree.joints)],
             [(np.asarray(m, float), np.asarray(o, float)) for m, o in
              (j.child_frame for j in tree.joints)]]
    frames = [np.hstack([m for m, _ in side]) for side in sides]
    origins = [np.column_stack([o for _, o in side]) for side in sides]
    outputs = step.map(len(tree.joints)).call(
        [r[:, parents], p[:, parents], r_dot[:, parents], p_dot[:, parents],
         r[:, children], p[:, children], r_dot[:, children], p_dot[:, children],
         ca.DM(frames[0]), ca.DM(origins[0]), ca.DM(frames[1]), ca.DM(origins[1])])
    return ca.Function("joint_relative_states", [q, q_dot], outputs, ["q", "q_dot"],
                       ["rotations", "gaps", "twists"])


@cache
def _relative_function() -> ca.Function:
    """tree_steps.relative_step as one SX Function."""
    shapes = [(3, 1), (4, 1), (3, 1), (4, 1)] * 2 + [(3, 3), (3, 1), (3, 3), (3, 1)]
    symbols = [ca.SX.sym(f"a{k}", *shape) for k, shape in enumerate(shapes)]
    return ca.Function("relative_step", symbols, list(relative_step.fn(*symbols)))
