"""Where each body's coordinates sit in q = [r (3 nb); p (4 nb)] and in the r-omega velocity
v = [r_dot (3 nb); omega_bar (3 nb)], and the gathers and scatters between per-instance
kernel outputs and the system's vectors and matrices (SX or MX alike)."""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.equations.derivatives import GROUND_POSE
from casmech.model.ir import GROUND_INDEX


class Layout:
    """Indices of the bodies' coordinates in q and v; ground maps past the end (padding)."""

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

    def pad_q(self, q, ground=None):
        """q followed by ground's pose: the constant GROUND_POSE, or `ground` (symbols)."""
        return ca.vertcat(q, ca.DM(GROUND_POSE) if ground is None else ground)

    def pad(self, vector, extra: int):
        return ca.vertcat(vector, ca.DM.zeros(extra))

    def p(self, vector):
        """The (4 x nb) Euler parameters of q (or of q_dot)."""
        return ca.reshape(vector[3 * self.nb:], 4, self.nb)


def scatter(n_rows: int, n_cols: int, triplets: list, values, sym=ca.MX):
    """The sparse (n_rows x n_cols) matrix whose (row, col) entry is values[position], from
    (row, col, position) triplets."""
    if not triplets:
        return sym(n_rows, n_cols)
    rows, cols, positions = zip(*triplets, strict=True)
    sparsity, mapping = ca.Sparsity.triplet(n_rows, n_cols, list(rows), list(cols), True)
    take = [0] * sparsity.nnz()
    for k, nonzero in enumerate(mapping):
        take[nonzero] = positions[k]
    return sym(sparsity, values[take])


def ordered(parts: list, order: list[int], sym=ca.MX):
    """Stack per-group row vectors and put them back in row order."""
    inverse = [int(k) for k in np.argsort(order)]
    return ca.vertcat(*parts)[inverse] if parts else sym(0, 1)
