"""The controls' shape over the control grid: piecewise constant (one value per interval) or
piecewise linear (one value per node, continuous), and the exact integral of u^T u."""

from __future__ import annotations

import casadi as ca

from casmech.core.records import record

SHAPES = ("constant", "linear")


@record
class ControlShape:
    kind: str = "constant"

    def values(self, intervals: int) -> int:
        """How many control values (columns) the grid holds."""
        return intervals + (self.kind == "linear")

    def at(self, u, k: int, s):
        """The control in interval k at fraction s of it (u: n_u x values)."""
        if self.kind == "constant":
            return u[:, k]
        return (1 - s) * u[:, k] + s * u[:, k + 1]

    def effort(self, u, step):
        """integral of u^T u dt, exact for the shape (step: the interval length)."""
        if self.kind == "constant":
            return step * ca.sumsqr(u)
        a, b = u[:, :-1], u[:, 1:]
        return step / 3 * (ca.sumsqr(a) + ca.sumsqr(b) + ca.sum1(ca.sum2(a * b)))
