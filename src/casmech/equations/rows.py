"""The constraint rows of a model over its row kernels (equations.row_kernels), evaluated by an
Evaluation: phi, phi_q, nu, gamma, phi_scaled, [Phi_r, Pi_bar], the r-omega gamma_hat and the
joints' reactions, each defined here once.

Each group of rows that shares a kernel gathers its bodies' coordinates by index (the row's
gather table: 7 per body it names; ground: a constant pose appended to q), calls the kernel over
its rows, and the per-row results are put back in row order (vectors) or scattered into the
system's sparsity pattern (Jacobians); the normalization rows p^T p - 1 follow, one per body.
Joint reactions sum the rows of each joint (one kernel per joint) into its column.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.equations import evaluation, inline
from casmech.equations import row_kernels as kernels
from casmech.equations.evaluation import Evaluation
from casmech.equations.layout import Layout, ordered, scatter
from casmech.model.ir import ModelIR
from casmech.numerics import element_sums

__all__ = ["BAKE_LIMIT", "Group", "Layout", "by_joint_keys", "constraints", "groups",
           "joint_f", "joint_rows", "joint_vectors", "ordered", "pattern", "reactions",
           "romega_gamma", "row_keys", "scatter", "stacked", "variations"]

# Most distinct row geometries baked into kernels (exact sparsity); a model with more passes
# the vectors as data (code independent of the geometry; see equations.row_kernels).
BAKE_LIMIT = 24


class Group:
    """The rows of one kernel: their indices, the data matrix and the gathered coordinates."""

    def __init__(self, key, members, layout: Layout, ev: Evaluation):
        self.key, self.members, self.layout, self.ev = key, members, layout, ev
        self.rows = [row for row, _ in members]
        self.count = len(members)
        self.columns = [[i for b in p.bodies for i in layout.q(b)] for _, p in members]
        self.v_columns = [[i for b in p.bodies for i in layout.v(b)] for _, p in members]
        pattern = evaluation.sparse_column(key.pattern)  # the kernels' c (row_kernels._Row)
        chosen = list(pattern.row())
        self.c = ev.constant(evaluation.columns(pattern, [
            [kernels.vectors_of(p)[k] for k in chosen] for _, p in members]))

    def x(self, q_padded):
        flat = [c for cs in self.columns for c in cs]
        return ca.reshape(q_padded[flat], self.key.width, self.count)

    def v(self, v_padded):
        flat = [c for cs in self.v_columns for c in cs]
        return ca.reshape(v_padded[flat], self.key.v_width, self.count)

    def f(self, t, scale=None):
        """[f, f', f''] of every row (3 x count): constants unless f depends on time (or the
        drivers are scaled by a symbol)."""
        if self.key.f_class == kernels.TIME or (
                scale is not None and self.key.f_class == kernels.CONSTANT):
            return ca.horzcat(*[kernels.taylor(p, t, 1.0 if scale is None else scale, self.ev)
                                for _, p in self.members])
        values = [[kernels.f_constant(p), 0.0, 0.0] for _, p in self.members]
        if evaluation.numeric([v for column in values for v in column]):
            return ca.DM(np.array(values, float).T)
        return self.ev.constant(evaluation.columns(ca.Sparsity.dense(3, 1), values))

    def call(self, kernel, *args):
        return self.ev.call(kernel, self.count, *args)

    def triplets(self, pattern, columns, offset: int, n: int, row_of=None) -> list:
        """(row, column, position) of every structural entry of the kernel's Jacobian row;
        positions count from `offset` in the stacked (width x count) kernel outputs."""
        width = len(columns[0])
        out = []
        for k, row in enumerate(row_of or self.rows):
            out += [(row, columns[k][c], offset + k * width + c) for c in pattern
                    if columns[k][c] < n]
        return out


_KEYS: dict[int, tuple] = {}  # id(ir) -> (ir, row keys): keys are computed once per model


def row_keys(ir: ModelIR) -> list:
    """Every row's kernel key; vectors baked while the model's numbers are numbers and it has
    at most BAKE_LIMIT distinct (kind, vectors), i.e. kernels."""
    cached = _KEYS.get(id(ir))
    if cached is not None and cached[0] is ir:
        return cached[1]
    numbers = all(evaluation.numeric(kernels.vectors_of(prim)) for prim in ir.primitives)
    keys = [kernels.key_of(prim, numbers) for prim in ir.primitives]
    if not numbers or len(set(keys)) > BAKE_LIMIT:
        keys = [kernels.key_of(prim, False) for prim in ir.primitives]
    _KEYS.clear()
    _KEYS[id(ir)] = (ir, keys)
    return keys


def groups(ir: ModelIR, layout: Layout, ev: Evaluation) -> list[Group]:
    """The rows by kernel key (built once per model and evaluation)."""
    def make() -> list[Group]:
        by_key: dict = {}
        for row, (prim, key) in enumerate(zip(ir.primitives, row_keys(ir), strict=True)):
            by_key.setdefault(key, []).append((row, prim))
        return [Group(key, members, layout, ev) for key, members in by_key.items()]
    return ev.kept(ir, "row groups", make)


def pattern(function: ca.Function, output: int) -> list[int]:
    """Columns of a kernel's row output that are not the constant 0: left out of the system's
    patterns, so that the DAE's Jacobian has no entry that is always zero."""
    value = function.call(function.sx_in())[output]
    sparsity = value.sparsity()
    return [c for c in range(sparsity.size2()) if sparsity.has_nz(0, c)
            and not value[0, c].is_zero()]


def _normalization_p(q, nb: int):
    return ca.reshape(q[3 * nb:], 4, nb)


def constraints(ir: ModelIR, ev: Evaluation, t, q, q_dot=None, scale=None,
                grounded=None) -> dict:
    """phi, phi_q, nu and (given q_dot) gamma; with `scale`: phi and phi_q with the drivers
    scaled (phi_scaled). Inline, `grounded`: (phi with ground's pose the symbols, those
    symbols) when already built (inline.grounded)."""
    layout = Layout(ir.n_bodies)
    if ev.inline:
        return inline.constraints(ir, ev, groups(ir, layout, ev), t, q, q_dot, scale,
                                  grounded)
    padded = layout.pad_q(q)
    padded_dot = None if q_dot is None else layout.pad(q_dot, 7)
    parts: dict = {"phi": [], "nu": [], "gamma": []}
    order, blocks, triplets, offset = [], [], [], 0
    for group in groups(ir, layout, ev):
        x, f = group.x(padded), group.f(t, scale)
        phi, jac, nu = group.call(kernels.constraint(group.key), x, group.c, f)
        parts["phi"].append(phi.T)
        parts["nu"].append(nu.T)
        if padded_dot is not None:
            parts["gamma"].append(group.call(kernels.gamma(group.key), x,
                                             group.x(padded_dot), group.c, f)[0].T)
        triplets += group.triplets(pattern(kernels.constraint(group.key), 1),
                                   group.columns, offset, layout.n)
        blocks.append(ca.vec(jac))
        offset += group.key.width * group.count
        order += group.rows
    nb, m = ir.n_bodies, len(ir.primitives)
    if nb:
        norm, norm_gamma, _ = kernels.normalization()
        p = _normalization_p(q, nb)
        phi, jac, nu = ev.call(norm, nb, p)
        parts["phi"].append(phi.T)
        parts["nu"].append(nu.T)
        if padded_dot is not None:
            parts["gamma"].append(ev.call(norm_gamma, nb, p, _normalization_p(q_dot, nb))[0].T)
        triplets += [(m + k, 3 * nb + 4 * k + c, offset + 4 * k + c) for k in range(nb)
                     for c in range(4)]
        blocks.append(ca.vec(jac))
        order += list(range(m, m + nb))
    values = ca.vertcat(*blocks) if blocks else ev.sym(0, 1)
    out = {name: ordered(value, order, ev.sym) for name, value in parts.items() if value}
    out["phi_q"] = scatter(m + nb, layout.n, triplets, values, ev.sym)
    return out


def variations(ir: ModelIR, ev: Evaluation, t, q, joint_rows_only: bool = False,
               derived: dict | None = None):
    """[Phi_r, Pi_bar] (rows of phi x 6 nb), the r-omega Jacobian; the normalization rows
    (zero in value) unless joint_rows_only. Inline: from phi_q (`derived`: constraints' output
    when already built)."""
    layout = Layout(ir.n_bodies)
    if ev.inline:
        phi_q = (derived or constraints(ir, ev, t, q))["phi_q"]
        return inline.variations(ir, phi_q[:len(ir.primitives), :] if joint_rows_only
                                 else phi_q, q)
    padded = layout.pad_q(q)
    blocks, triplets, offset = [], [], 0
    for group in groups(ir, layout, ev):
        kernel = kernels.variation(group.key)
        blocks.append(ca.vec(group.call(kernel, group.x(padded), group.c, group.f(t))[0]))
        triplets += group.triplets(pattern(kernel, 0), group.v_columns, offset, layout.n_v)
        offset += group.key.v_width * group.count
    nb, m = ir.n_bodies, len(ir.primitives)
    if nb and not joint_rows_only:
        pi_bar = ev.call(kernels.normalization()[2], nb, _normalization_p(q, nb))[0]
        triplets += [(m + k, 3 * nb + 3 * k + c, offset + 3 * k + c) for k in range(nb)
                     for c in range(3)]
        blocks.append(ca.vec(pi_bar))
    values = ca.vertcat(*blocks) if blocks else ev.sym(0, 1)
    return scatter(m if joint_rows_only else m + nb, layout.n_v, triplets, values, ev.sym)


def romega_gamma(ir: ModelIR, ev: Evaluation, t, q, v, q_dot=None, derived: dict | None = None):
    """gamma_hat of the joint rows (row_kernels.romega_gamma); inline: of the whole model, at
    q_dot = q_dot(q, v) (`derived`: as variations')."""
    layout = Layout(ir.n_bodies)
    if ev.inline:
        m = len(ir.primitives)
        if not m:
            return ev.sym(0, 1)
        derived = derived or constraints(ir, ev, t, q)
        jacobian = variations(ir, ev, t, q, True, derived)
        return inline.romega_gamma(jacobian, derived["nu"][:m], t, q, v, q_dot)
    padded, padded_v = layout.pad_q(q), layout.pad(v, 6)
    parts, order = [], []
    for group in groups(ir, layout, ev):
        parts.append(group.call(kernels.romega_gamma(group.key), group.x(padded),
                                group.v(padded_v), group.c, group.f(t))[0].T)
        order += group.rows
    return ordered(parts, order, ev.sym)


def joint_rows(ir: ModelIR) -> list[list[int]]:
    """Rows grouped by joint (one element each: their bodies are the same); a row whose bodies
    differ from the rest of its joint's, and a row of no joint, alone."""
    out, covered = [], set()
    for joint in ir.joints:
        rows = list(joint.rows)
        bodies = {ir.primitives[k].bodies for k in rows}
        out += [rows] if len(bodies) == 1 else [[k] for k in rows]
        covered.update(rows)
    return [rows for rows in out if rows] + [[k] for k in range(len(ir.primitives))
                                             if k not in covered]


def by_joint_keys(ir: ModelIR) -> dict[tuple, list[list[int]]]:
    """joint_rows grouped by the tuple of their rows' kernel keys (one kernel per group)."""
    keys, out = row_keys(ir), {}
    for rows in joint_rows(ir):
        out.setdefault(tuple(keys[k] for k in rows), []).append(rows)
    return out


def joint_f(ir: ModelIR, keys: tuple, members: list[list[int]], t, ev: Evaluation):
    """[f, f', f''] of every row of every instance ((3 rows) x count)."""
    return ca.horzcat(*[ca.vertcat(*[kernels.taylor_or_constant(ir.primitives[k], key, t, ev)
                                     for k, key in zip(rows, keys, strict=True)])
                        for rows in members])


def joint_vectors(ir: ModelIR, keys: tuple, members: list[list[int]], pattern_of,
                  include=lambda key: True) -> list:
    """Per instance, the vector entries of its rows that `include` takes, each on its kernel's
    pattern (pattern_of(key))."""
    out = []
    for rows in members:
        entries = []
        for k, key in zip(rows, keys, strict=True):
            if include(key):
                vectors = kernels.vectors_of(ir.primitives[k])
                entries += [vectors[c] for c in pattern_of(key).row()]
        out.append(entries)
    return out


def reactions(ir: ModelIR, ev: Evaluation, t, q, lam, grounded=None) -> tuple:
    """(force, torque) of every joint's rows on its body_j (3 x joints): one kernel call per
    joint (row_kernels.joint_reaction), each column added into its joint's; inline: by AD of
    the expanded rows."""
    layout = Layout(ir.n_bodies)
    if ev.inline:
        return inline.reactions(ir, ev, groups(ir, layout, ev), t, q, lam, grounded)
    padded = layout.pad_q(q)
    joint_of = {row: j for j, joint in enumerate(ir.joints) for row in joint.rows}
    forces, torques, columns = [], [], []
    for keys, members in by_joint_keys(ir).items():
        first = [ir.primitives[rows[0]] for rows in members]
        x = ca.reshape(padded[[c for p in first for b in p.bodies for c in layout.q(b)]],
                       keys[0].width, len(members))
        vectors = joint_vectors(ir, keys, members,
                                lambda key: kernels.reaction(key).sparsity_in(1))
        c = ev.constant(stacked(vectors))
        multipliers = ca.reshape(lam[[k for rows in members for k in rows]], len(keys),
                                 len(members))
        points = ev.constant(evaluation.columns(ca.Sparsity.dense(3, 1), [
            evaluation.entries(ir.joints[joint_of[rows[0]]].point_i) if rows[0] in joint_of
            else [0.0] * 3 for rows in members]))
        kernel = kernels.joint_reaction(keys)
        force, torque = ev.call(kernel, len(members), x, c, joint_f(ir, keys, members, t, ev),
                                multipliers, points)
        forces.append(force)
        torques.append(torque)
        columns.append((kernel, [joint_of.get(rows[0], -1) for rows in members]))
    n_joints = len(ir.joints)
    return tuple(_joint_columns(n_joints, columns, output, parts, ev)
                 for output, parts in enumerate((forces, torques)))


def stacked(vectors: list[list]):
    """(entries x count) of per-instance entry lists of equal length."""
    count = len(vectors)
    size = len(vectors[0]) if vectors else 0
    return evaluation.columns(ca.Sparsity.dense(size, 1), vectors) if size else ca.DM(0, count)


def _joint_columns(n_joints: int, groups: list, output: int, parts: list, ev: Evaluation):
    """The (3 x joints) matrix of the kernels' outputs added into their joints' columns
    (column -1: a row of no joint, dropped); the entries a kernel's output leaves structurally
    zero are left out."""
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
        return ev.sym(3, n_joints)
    return element_sums.assemble([(3, n_joints, rows, cols, positions)], parts)[0]
