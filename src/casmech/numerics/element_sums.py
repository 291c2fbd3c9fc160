"""Sums of elements: a vector function r(u) = sum over elements e of S_e k_e(G_e u, d_e), where
each element's kernel k_e is a small SX function of a few entries of u (gathered by G_e) and of
data d_e (time, masks, geometry: not differentiated), and S_e adds its outputs into rows of r.
Instances of one kernel form a Group, evaluated by one mapped call.

The Jacobian dr/du is assembled the same way from each kernel's own SX Jacobian (a small
sparse matrix per instance), every entry added in place into the global non-zeros (add_into),
so its cost is that of the kernels' Jacobians plus one pass over their non-zeros, and its code
does not grow with the number of instances (only index tables do). CasADi's MX Jacobian of a
mapped residual instead costs a forward sweep of every kernel per colour of the Jacobian,
slower than the interpreted SX Jacobian, where this is faster
(docs/decisions/codegen-element-residuals.md).
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.numerics import instances

DROPPED = -1  # an output index that is not added anywhere (e.g. ground's rows)


@record
class Group:
    """Instances of one kernel (y [n_y], d [n_d]) -> out [n_out] (SX).

    inputs: (count, n_y) indices into u, or >= len(u) for an entry of the padding (a constant
    the kernel ignores, e.g. ground's coordinates); outputs: (count, n_out) rows of r, or
    DROPPED; data: (n_d, count), DM or MX."""

    kernel: ca.Function
    inputs: np.ndarray
    outputs: np.ndarray
    data: object

    @property
    def count(self) -> int:
        return len(self.inputs)


@record
class ElementSum:
    """r(u) (n_rows) as the sum of its groups' contributions; u is followed by the constant
    `padding` (the entries that inputs >= n_u pick)."""

    n_rows: int
    n_u: int
    groups: tuple[Group, ...]
    padding: ca.DM = ca.DM(0, 1)

    def _padded(self, u):
        return ca.vertcat(u, self.padding) if self.padding.numel() else u

    @staticmethod
    def _gathered(padded, group: Group):
        return ca.reshape(padded[[int(i) for i in group.inputs.ravel()]],
                          group.inputs.shape[1], group.count)

    def value(self, u) -> ca.MX:
        """r(u), dense."""
        padded = self._padded(u)
        parts, rows, positions, offset = [], [], [], 0
        for group in self.groups:
            out = instances.plain_map(group.kernel, group.count)(self._gathered(padded, group),
                                                                 group.data)
            keep = group.outputs.ravel() != DROPPED  # row-major: instance k, output o
            rows.append(group.outputs.ravel()[keep])
            positions.append(offset + np.flatnonzero(keep))
            parts.append(ca.vec(out))  # column k holds instance k: the same order
            offset += out.numel()
        rows, positions = np.concatenate([[], *rows]), np.concatenate([[], *positions])
        return assemble([(self.n_rows, 1, rows, np.zeros(len(rows), int), positions)],
                         parts, dense=True)[0]

    def jacobian(self, u, row_blocks=(None,), column_blocks=(None,)) -> list[ca.MX]:
        """dr/du as sparse blocks: for every row block (start, stop) and column block, in that
        order (None: all rows or columns)."""
        padded = self._padded(u)
        parts, triplets, offset = [], [], 0
        for group in self.groups:
            local, pattern = jacobian_kernel(group.kernel)
            out_index, in_index = pattern.get_triplet()
            nnz = pattern.nnz()
            rows = group.outputs[:, out_index]  # (count, nnz)
            cols = group.inputs[:, in_index]
            keep = (rows != DROPPED) & (cols < self.n_u)
            position = offset + np.arange(group.count)[:, None] * nnz + np.arange(nnz)[None, :]
            triplets.append((rows[keep], cols[keep], position[keep]))
            parts.append(ca.vec(instances.plain_map(local, group.count)(
                self._gathered(padded, group), group.data)))
            offset += nnz * group.count
        rows, cols, positions = (np.concatenate([[], *items]).astype(int)
                                 for items in zip(*triplets, strict=True)) \
            if triplets else (np.zeros(0, int),) * 3
        blocks = []
        for row_block in row_blocks:
            r0, r1 = row_block or (0, self.n_rows)
            for column_block in column_blocks:
                c0, c1 = column_block or (0, self.n_u)
                inside = (rows >= r0) & (rows < r1) & (cols >= c0) & (cols < c1)
                blocks.append((r1 - r0, c1 - c0, rows[inside] - r0, cols[inside] - c0,
                               positions[inside]))
        return assemble(blocks, parts)


@lru_cache(maxsize=512)
def jacobian_kernel(kernel: ca.Function) -> tuple[ca.Function, ca.Sparsity]:
    """(y, d) -> the non-zeros of d out / d y (one column), and their pattern (out x y): the
    kernel's own SX Jacobian."""
    y, d = kernel.sx_in()
    jac = ca.jacobian(kernel(y, d), y)
    return ca.Function(f"jac_{kernel.name()}", [y, d], [jac.nz[:] if jac.nnz() else ca.SX(0, 1)],
                       ["y", "d"], ["jac"]), jac.sparsity()


def assemble(blocks: list[tuple], parts: list, dense: bool = False) -> list[ca.MX]:
    """Sparse matrices from (n_rows, n_cols, rows, cols, positions) triplets into the stacked
    parts: entry (rows[k], cols[k]) is the sum of the stacked entries positions[k] (duplicates
    add up); dense: dense blocks. Every block's non-zeros are one slice of a single vector into
    which each part is added in place (add_into)."""
    sizes = np.cumsum([0] + [part.numel() for part in parts])
    sparsities, target = [], np.full(sizes[-1], -1, dtype=int)
    for n_rows, n_cols, rows, cols, positions in blocks:
        rows, cols = [int(r) for r in rows], [int(c) for c in cols]
        if dense:
            sparsity = ca.Sparsity.dense(n_rows, n_cols)
            mapping = np.asarray(rows, int) + n_rows * np.asarray(cols, int)
        else:
            sparsity, mapping = ca.Sparsity.triplet(n_rows, n_cols, rows, cols, True)
        target[np.asarray(positions, int)] = sum(s.nnz() for s in sparsities) + np.asarray(
            mapping, int)
        sparsities.append(sparsity)
    total = sum(s.nnz() for s in sparsities)
    target[target < 0] = total  # entries no block takes go to a last, discarded slot
    values = add_into(total + 1, [(ca.densify(ca.vec(part)), target[sizes[g]:sizes[g + 1]])
                                  for g, part in enumerate(parts)])
    out, start = [], 0
    for sparsity in sparsities:
        out.append(ca.MX(sparsity, values[start:start + sparsity.nnz()]))
        start += sparsity.nnz()
    return out


def summed(n_rows: int, n_cols: int, rows, cols, parts: list) -> ca.MX:
    """The sparse (n_rows x n_cols) matrix whose entry (rows[k], cols[k]) is the sum of the
    k-th entries of the stacked parts (each vectorized column by column)."""
    positions = np.arange(sum(part.numel() for part in parts))
    return assemble([(n_rows, n_cols, rows, cols, positions)], parts)[0]


def add_into(size: int, terms: list[tuple]) -> ca.MX:
    """The vector of `size` zeros with every (values, targets) term added in place:
    out[targets[k]] += values[k] (duplicates add up). CasADi has this operation (AddNonzeros:
    one C loop, no copy) as the adjoint of a gather, which is how it is obtained here."""
    if not terms:
        return ca.MX.zeros(size)
    out = ca.MX.sym("out", size)
    gathered = [out[[int(k) for k in targets]] for _, targets in terms]
    return ca.reverse(gathered, [out], [[values for values, _ in terms]])[0][0]
