"""The constraint family (phi, phi_q, nu, gamma, variations, phi_scaled, romega_jacobian,
romega_nu, romega_gamma, reactions) as MX functions over row kernels (equations.mapped.rows) mapped
over
their rows: code whose size does not grow with the number of joints.

Each group of rows that shares a kernel gathers its bodies' coordinates by index (ground: a
constant pose appended to q), calls the kernel once through casadi's map, and the per-row
results are put back in row order (vectors) or scattered into the unrolled sparsity pattern
(Jacobians). Joint reactions sum the rows of each joint with a constant matrix. The results equal
the unrolled SX functions (equations.functions) in value and sparsity, except that entries which
are the constant 0 in a kernel are left out of the patterns (see _pattern), which gives the
DAE's Jacobian exactly the unrolled sparsity: tests/codegen/test_mapped.py.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache

import casadi as ca
import numpy as np

from casmech.equations.assemble import GROUND_POSE
from casmech.equations.mapped import rows as kernels_of
from casmech.equations.mapped.rows import ROW, V_ROW
from casmech.model.ir import GROUND_INDEX, ModelIR
from casmech.numerics import element_sums

# Most distinct row geometries baked into kernels (exact unrolled sparsity); a model with more
# passes the vectors as data (code independent of the geometry; see equations.mapped.rows).
BAKE_LIMIT = 24


# Derivative directions per call of a kernel's derivative. casadi batches up to 64 by default:
# code 64 times the kernel's derivative; 1 gives less C, built sooner
# (docs/decisions/codegen-flags.md).
MAX_DIRECTIONS = 1


def mapped(kernel: ca.Function, count: int) -> ca.Function:
    """The kernel evaluated over `count` instances (columns), serially."""
    return kernel.map(f"map{count}_{kernel.name()}", "serial", count, [], [],
                      {"max_num_dir": MAX_DIRECTIONS})


class Layout:
    """Indices of the bodies' coordinates in q = [r (3 nb); p (4 nb)] and in the r-omega
    velocity v = [r_dot (3 nb); omega_bar (3 nb)]; ground maps past the end (padding)."""

    def __init__(self, nb: int):
        self.nb, self.n, self.n_v = nb, 7 * nb, 6 * nb

    def q(self, k: int) -> list[int]:
        if k == GROUND_INDEX:
            return list(range(self.n, self.n + 7))
        return [3 * k + i for i in range(3)] + [3 * self.nb + 4 * k + i for i in range(4)]

    def v(self, k: int) -> list[int]:
        if k == GROUND_INDEX:
            return list(range(self.n_v, self.n_v + 6))
        return [3 * k + i for i in range(3)] + [3 * self.nb + 3 * k + i for i in range(3)]

    def pad_q(self, q):
        return ca.vertcat(q, ca.DM(GROUND_POSE))

    def pad(self, vector, extra: int):
        return ca.vertcat(vector, ca.DM.zeros(extra))


def scatter(n_rows: int, n_cols: int, triplets: list, values) -> ca.MX:
    """The sparse (n_rows x n_cols) matrix whose (row, col) entry is values[position], from
    (row, col, position) triplets."""
    if not triplets:
        return ca.MX(n_rows, n_cols)
    rows, cols, positions = zip(*triplets, strict=True)
    sparsity, mapping = ca.Sparsity.triplet(n_rows, n_cols, list(rows), list(cols), True)
    take = [0] * sparsity.nnz()
    for k, nonzero in enumerate(mapping):
        take[nonzero] = positions[k]
    return ca.MX(sparsity, values[take])


def ordered(parts: list, order: list[int]):
    """Stack per-group row vectors and put them back in row order."""
    inverse = [int(k) for k in np.argsort(order)]
    return ca.vertcat(*parts)[inverse] if parts else ca.MX(0, 1)


class Group:
    """The rows of one kernel: their indices, the data matrix and the gathered coordinates."""

    def __init__(self, key, members, layout: Layout):
        self.key, self.members, self.layout = key, members, layout
        self.rows = [row for row, _ in members]
        self.count = len(members)
        self.columns = [layout.q(p.body_i) + layout.q(p.body_j) for _, p in members]
        self.v_columns = [layout.v(p.body_i) + layout.v(p.body_j) for _, p in members]
        pattern = kernels_of.constraint(key).sparsity_in(1)
        self.c = ca.DM(ca.repmat(pattern, 1, self.count), np.concatenate(
            [kernels_of.vectors_of(p)[list(pattern.row())] for _, p in members]))

    def x(self, q_padded):
        flat = [c for cs in self.columns for c in cs]
        return ca.reshape(q_padded[flat], ROW, self.count)

    def v(self, v_padded):
        flat = [c for cs in self.v_columns for c in cs]
        return ca.reshape(v_padded[flat], V_ROW, self.count)

    def f(self, t, scale=None):
        """[f, f', f''] of every row (3 x count): constants unless f depends on time (or the
        drivers are scaled by a symbol)."""
        if self.key.f_class == kernels_of.TIME or (
                scale is not None and self.key.f_class == kernels_of.CONSTANT):
            return ca.horzcat(*[kernels_of.taylor(p, t, 1.0 if scale is None else scale)
                                for _, p in self.members])
        values = [kernels_of.f_constant(p) for _, p in self.members]
        return ca.DM(np.vstack([values, np.zeros((2, self.count))]))

    def call(self, kernel, *args):
        return mapped(kernel, self.count)(*args)

    def triplets(self, pattern, columns, offset: int, n: int, row_of=None) -> list:
        """(row, column, position) of every structural entry of the kernel's Jacobian row;
        positions count from `offset` in the stacked (width x count) kernel outputs."""
        width = len(columns[0])
        out = []
        for k, row in enumerate(row_of or self.rows):
            out += [(row, columns[k][c], offset + k * width + c) for c in pattern
                    if columns[k][c] < n]
        return out


def row_keys(ir: ModelIR) -> list:
    """Every row's kernel key; vectors baked while the model has at most BAKE_LIMIT distinct
    (kind, vectors), i.e. kernels."""
    keys = [kernels_of.key_of(prim, True) for prim in ir.primitives]
    if len(set(keys)) > BAKE_LIMIT:
        keys = [kernels_of.key_of(prim, False) for prim in ir.primitives]
    return keys


def groups(ir: ModelIR, layout: Layout) -> list[Group]:
    by_key: dict = {}
    for row, (prim, key) in enumerate(zip(ir.primitives, row_keys(ir), strict=True)):
        by_key.setdefault(key, []).append((row, prim))
    return [Group(key, members, layout) for key, members in by_key.items()]


def _pattern(function: ca.Function, output: int) -> list[int]:
    """Columns of a kernel's row output that are not the constant 0. (The unrolled functions
    list some constant zeros in their patterns; they vanish when the DAE is formed there, so
    leaving them out here gives the DAE Jacobian the unrolled sparsity.)"""
    value = function.call(function.sx_in())[output]
    sparsity = value.sparsity()
    return [c for c in range(sparsity.size2()) if sparsity.has_nz(0, c)
            and not value[0, c].is_zero()]


def rp_constraints(ir: ModelIR, t, q, q_dot, scale=None) -> dict:
    """phi, phi_q, nu, gamma (scale: phi and phi_q with drivers scaled, for phi_scaled)."""
    layout = Layout(ir.n_bodies)
    padded, padded_dot = layout.pad_q(q), layout.pad(q_dot, 7)
    parts: dict = {"phi": [], "nu": [], "gamma": []}
    order, blocks, triplets, offset = [], [], [], 0
    for group in groups(ir, layout):
        x, f = group.x(padded), group.f(t, scale)
        phi, jac, nu = group.call(kernels_of.constraint(group.key), x, group.c, f)
        parts["phi"].append(phi.T)
        parts["nu"].append(nu.T)
        if scale is None:
            parts["gamma"].append(group.call(kernels_of.gamma(group.key), x,
                                             group.x(padded_dot), group.c, f).T)
        triplets += group.triplets(_pattern(kernels_of.constraint(group.key), 1),
                                   group.columns, offset, layout.n)
        blocks.append(ca.vec(jac))
        offset += ROW * group.count
        order += group.rows
    nb, m = ir.n_bodies, len(ir.primitives)
    if nb:
        norm, norm_gamma, _ = kernels_of.normalization()
        p, p_dot = ca.reshape(q[3 * nb:], 4, nb), ca.reshape(q_dot[3 * nb:], 4, nb)
        phi, jac, nu = mapped(norm, nb)(p)
        parts["phi"].append(phi.T)
        parts["nu"].append(nu.T)
        if scale is None:
            parts["gamma"].append(mapped(norm_gamma, nb)(p, p_dot).T)
        triplets += [(m + k, 3 * nb + 4 * k + c, offset + 4 * k + c) for k in range(nb)
                     for c in range(4)]
        blocks.append(ca.vec(jac))
        order += list(range(m, m + nb))
    values = ca.vertcat(*blocks) if blocks else ca.MX(0, 1)
    out = {name: ordered(value, order) for name, value in parts.items() if value}
    out["phi_q"] = scatter(m + nb, layout.n, triplets, values)
    return out


def variations(ir: ModelIR, t, q, joint_rows_only: bool = False) -> ca.MX:
    """[Phi_r, Pi_bar] (rows of phi x 6 nb), the r-omega Jacobian; the normalization rows
    (zero in value) unless joint_rows_only."""
    layout = Layout(ir.n_bodies)
    padded = layout.pad_q(q)
    blocks, triplets, offset = [], [], 0
    for group in groups(ir, layout):
        kernel = kernels_of.variation(group.key)
        blocks.append(ca.vec(group.call(kernel, group.x(padded), group.c, group.f(t))))
        triplets += group.triplets(_pattern(kernel, 0), group.v_columns, offset, layout.n_v)
        offset += V_ROW * group.count
    nb, m = ir.n_bodies, len(ir.primitives)
    if nb and not joint_rows_only:
        pi_bar = mapped(kernels_of.normalization()[2], nb)(ca.reshape(q[3 * nb:], 4, nb))
        triplets += [(m + k, 3 * nb + 3 * k + c, offset + 3 * k + c) for k in range(nb)
                     for c in range(3)]
        blocks.append(ca.vec(pi_bar))
    values = ca.vertcat(*blocks) if blocks else ca.MX(0, 1)
    return scatter(m if joint_rows_only else m + nb, layout.n_v, triplets, values)


def romega_gamma(ir: ModelIR, t, q, v) -> ca.MX:
    layout = Layout(ir.n_bodies)
    padded, padded_v = layout.pad_q(q), layout.pad(v, 6)
    parts, order = [], []
    for group in groups(ir, layout):
        parts.append(group.call(kernels_of.romega_gamma(group.key), group.x(padded),
                                group.v(padded_v), group.c, group.f(t)).T)
        order += group.rows
    return ordered(parts, order)


def joint_rows(ir: ModelIR) -> list[list[int]]:
    """Rows grouped by joint (one element each: their bodies are the same); a row whose bodies
    differ from the rest of its joint's, and a row of no joint, alone."""
    out, covered = [], set()
    for joint in ir.joints:
        rows = list(joint.rows)
        pairs = {(ir.primitives[k].body_i, ir.primitives[k].body_j) for k in rows}
        out += [rows] if len(pairs) == 1 else [[k] for k in rows]
        covered.update(rows)
    return [rows for rows in out if rows] + [[k] for k in range(len(ir.primitives))
                                             if k not in covered]


def by_joint_keys(ir: ModelIR) -> dict[tuple, list[list[int]]]:
    """joint_rows grouped by the tuple of their rows' kernel keys (one kernel per group)."""
    keys, out = row_keys(ir), {}
    for rows in joint_rows(ir):
        out.setdefault(tuple(keys[k] for k in rows), []).append(rows)
    return out


@lru_cache(maxsize=256)
def joint_reaction(keys: tuple) -> ca.Function:
    """(x, c, f, lam, s) -> (force, torque) of one joint's rows together (x [14]; c, f, lam:
    every row's, stacked): the sum of their equations.mapped.rows.reaction."""
    rows = [kernels_of.reaction(key) for key in keys]
    c = ca.SX.sym("c", sum(r.nnz_in(1) for r in rows))
    f, lam, s = ca.SX.sym("f", 3 * len(keys)), ca.SX.sym("lam", len(keys)), ca.SX.sym("s", 3)
    x = ca.SX.sym("x", ROW)
    force, torque, start = ca.SX(3, 1), ca.SX(3, 1), 0
    for k, row in enumerate(rows):
        pattern = row.sparsity_in(1)
        f_k, t_k = row(x, ca.SX(pattern, c[start:start + pattern.nnz()]), f[3 * k:3 * k + 3],
                       lam[k], s)
        force, torque, start = force + f_k, torque + t_k, start + pattern.nnz()
    digest = hashlib.sha256(repr(keys).encode()).hexdigest()[:10]
    return ca.Function(f"joint_reaction_{digest}", [x, c, f, lam, s], [force, torque],
                       ["x", "c", "f", "lam", "s"], ["force", "torque"])


def reactions(ir: ModelIR, t, q, lam) -> tuple:
    """(force, torque) of every joint on its body_j (3 x joints): one kernel call per joint
    (joint_reaction), each column added into its joint's (numerics.element_sums.summed)."""
    layout = Layout(ir.n_bodies)
    padded = layout.pad_q(q)
    joint_of = {row: j for j, joint in enumerate(ir.joints) for row in joint.rows}
    forces, torques, groups = [], [], []
    for keys, members in by_joint_keys(ir).items():
        first = [ir.primitives[rows[0]] for rows in members]
        x = ca.reshape(padded[[c for p in first for c in layout.q(p.body_i) + layout.q(p.body_j)]],
                       ROW, len(members))
        c = ca.DM(np.array([np.concatenate([np.zeros(0)] + [kernels_of.vectors_of(
            ir.primitives[k])[list(kernels_of.reaction(key).sparsity_in(1).row())]
            for k, key in zip(rows, keys, strict=True)]) for rows in members]).reshape(
            len(members), -1).T)
        f = ca.horzcat(*[ca.vertcat(*[taylor_or_constant(ir.primitives[k], key, t)
                                      for k, key in zip(rows, keys, strict=True)])
                         for rows in members])
        multipliers = ca.reshape(lam[[k for rows in members for k in rows]], len(keys),
                                 len(members))
        points = ca.DM(np.array([ir.joints[joint_of[rows[0]]].point_i if rows[0] in joint_of
                                 else np.zeros(3) for rows in members], float).T)
        kernel = joint_reaction(keys)
        force, torque = mapped(kernel, len(members))(x, c, f, multipliers, points)
        forces.append(force)
        torques.append(torque)
        groups.append((kernel, [joint_of.get(rows[0], -1) for rows in members]))
    n_joints = len(ir.joints)
    return tuple(_joint_columns(n_joints, groups, output, parts)
                 for output, parts in enumerate((forces, torques)))


def _joint_columns(n_joints: int, groups: list, output: int, parts: list) -> ca.MX:
    """The (3 x joints) matrix of the kernels' outputs added into their joints' columns
    (column -1: a row of no joint, dropped); the entries a kernel's output leaves structurally
    zero are left out, as they are in the unrolled reactions."""
    rows, cols, positions, offset = [], [], [], 0
    for kernel, columns in groups:
        nonzero = sorted(set(kernel.sparsity_out(output).row()))
        for k, column in enumerate(columns):
            if column >= 0:
                rows += nonzero
                cols += [column] * len(nonzero)
                positions += [offset + 3 * k + a for a in nonzero]
        offset += 3 * len(columns)
    if not rows:
        return ca.MX(3, n_joints)
    return element_sums.assemble([(3, n_joints, rows, cols, positions)], parts)[0]


def taylor_or_constant(prim, key, t):
    """[f, f', f''] of a row at t: its Taylor coefficients when f depends on time."""
    if key.f_class == kernels_of.TIME:
        return kernels_of.taylor(prim, t)
    return ca.DM([kernels_of.f_constant(prim), 0.0, 0.0])
