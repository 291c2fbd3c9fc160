"""Structural checks at a configuration: DOF, rank, redundant rows mapped to joints and lines."""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.core.options import LinearAlgebra
from casmech.core.records import record
from casmech.equations.functions import SystemFunctions
from casmech.errors import BodyName
from casmech.model.ir import RowInfo

LIMITS = LinearAlgebra()  # the defaults (core.options)


@record
class Structure:
    """The constraint rows' structure at a pose: coordinates, rows, rank, the redundant
    rows, the nominal degrees of freedom and the rows kept."""

    n_coordinates: int
    n_rows: int
    rank: int
    redundant: tuple[RowInfo, ...]  # rows that depend on earlier rows (file order)
    nominal_dof: int  # 6 nb minus the joint rows (Gruebler count)
    independent: tuple[int, ...] = ()  # indices of the rows kept, in row order

    @property
    def dof(self) -> int:
        return self.n_coordinates - self.rank

    def summary(self) -> str:
        return "\n".join([f"coordinates: {self.n_coordinates}  constraint rows: {self.n_rows} "
                          f"(incl. normalization)  rank: {self.rank}", *self.dof_lines()])

    def dof_lines(self) -> list[str]:
        """DOF in words: coordinates less the rank of the rows, against the count of 6 per
        body less 1 per joint row (Gruebler), which redundant rows make smaller; then each
        redundant row with its joint and YAML line."""
        bodies = self.n_coordinates // 7
        joint_rows = self.n_rows - bodies
        extra = len(self.redundant)
        count = f"6 per body - 1 per joint row: 6 x {bodies} - {joint_rows} = {self.nominal_dof}"
        if extra:
            words = ("row (below) repeats what the rows before it constrain and removes"
                     if extra == 1 else "rows (below) repeat what the rows before them "
                     "constrain and remove")
            count += f"; {extra} redundant {words} no freedom: {self.nominal_dof} + {extra} = " \
                     f"{self.dof}"
        lines = [f"degrees of freedom: {self.dof} = {self.n_coordinates} coordinates - rank "
                 f"{self.rank} of the {self.n_rows} constraint rows", f"  ({count})"]
        for row in self.redundant:
            where = f"{row.source}: " if row.source else ""
            lines.append(f"  redundant: {where}{row.label}")
        return lines


def independent_rows(matrix, limits: LinearAlgebra = LIMITS) -> list[bool]:
    """Greedy in row order: is row k farther than limits.rank_tolerance * max(|matrix|_2, 1)
    from the span of the rows kept before it? (numeric_qr.independent_rows: a sparse QR, so the
    work follows the factors' fill, not rows x columns)."""
    from casmech.numerics import numeric_qr

    matrix = ca.DM(matrix)
    scale = max(numeric_qr.norm2(matrix, limits=limits), 1.0)
    return numeric_qr.independent_rows(matrix, limits.rank_tolerance, scale, limits)


def structure(functions: SystemFunctions, t: float, q: np.ndarray,
              limits: LinearAlgebra = LIMITS) -> Structure:
    """Rank and redundancy. The normalization rows are scanned first (they are never
    redundant), then the joint rows in file order, so a redundancy is blamed on the later joint."""
    phi_q = functions["phi_q"](t, q)
    n_joint_rows = functions.n_rows - functions.n_bodies
    order = _scan_order(functions)
    keep = dict(zip(order, independent_rows(phi_q[order, :], limits), strict=True))
    redundant = tuple(row for k, row in enumerate(functions.rows) if not keep[k])
    independent = tuple(k for k in range(functions.n_rows) if keep[k])
    return Structure(functions.n_coordinates, functions.n_rows, len(independent), redundant,
                     6 * functions.n_bodies - n_joint_rows, independent)


def _scan_order(functions: SystemFunctions) -> list[int]:
    """Rows of Phi in the order structure scans them: normalization first, then the joints."""
    n_joint_rows = functions.n_rows - functions.n_bodies
    return list(range(n_joint_rows, functions.n_rows)) + list(range(n_joint_rows))


def worst_joints(functions: SystemFunctions, residual: np.ndarray, count: int = 3):
    """(joint name, source, largest |residual| of its rows), worst first, for failure messages."""
    by_joint: dict[str, tuple[object, float]] = {}
    for row, value in zip(functions.rows, np.abs(np.ravel(residual)), strict=True):
        name = BodyName(row.joint) if row.kind == "normalization" else row.joint
        source, worst = by_joint.get(name, (row.source, 0.0))
        by_joint[name] = (source, max(worst, float(value)))
    ranked = sorted(by_joint.items(), key=lambda item: -item[1][1])
    return [(name, source, value) for name, (source, value) in ranked[:count]]


def dependent_joints(functions: SystemFunctions, phi_q, count: int = 3,
                     limits: LinearAlgebra = LIMITS):
    """Joints whose rows became dependent: a unit combination u of Phi_q's rows with
    Phi_q^T u ~ 0 weighs each row by its part in the dependency. Up to
    limits.dense_svd_entries entries u is the left singular vector of the smallest singular
    value; above, the row (in structure's scan order) closest to the span of the rows before
    it, combined with them by least squares (sparse: numeric_qr)."""
    from casmech.numerics import numeric_qr

    rows, columns = phi_q.shape
    if rows * columns <= limits.dense_svd_entries:
        u, s, _ = np.linalg.svd(np.array(ca.DM(phi_q)) if isinstance(phi_q, ca.DM) else phi_q)
        return worst_joints(functions, np.abs(u[:, s.size - 1]), count)
    order = _scan_order(functions)[:columns]
    a = ca.DM(phi_q)[order, :]
    k = int(np.argmin(numeric_qr.NumericQR(a.T, order=False).diagonal()))
    weights = np.zeros(rows)
    weights[order[k]] = 1.0
    if k:
        earlier = numeric_qr.NumericQR(a[:k, :].T)
        weights[order[:k]] = -earlier.solve(np.array(a[k, :]).ravel())
    return worst_joints(functions, np.abs(weights) / np.linalg.norm(weights), count)
