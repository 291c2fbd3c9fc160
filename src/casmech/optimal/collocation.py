"""Direct collocation (rockit's DirectCollocation): the transcription of an ODE
x' = f(t, x, c) by a polynomial of degree `degree` on each of `elements` equal elements per
control interval, collocated at the Radau IIA points (order 2 degree - 1; the last point is
the element's end) or the Gauss-Legendre points (order 2 degree; the end extrapolated).

Per element: the states at its `degree` points are variables; the polynomial through the
element's start and them has slope f at every point.
"""

from __future__ import annotations

from functools import cached_property

import casadi as ca
import numpy as np

from casmech.core.records import record

SCHEMES = ("radau", "legendre")


@record
class DirectCollocation:
    degree: int = 3
    scheme: str = "radau"
    elements: int = 1  # elements per control interval

    @cached_property
    def tau(self) -> np.ndarray:
        return np.append(0.0, ca.collocation_points(self.degree, self.scheme))

    @cached_property
    def coefficients(self) -> tuple[np.ndarray, np.ndarray]:
        """(C, D): C[r, j] the derivative of the r-th Lagrange basis polynomial at tau_j,
        D[r] its value at 1 (the element's end)."""
        tau, size = self.tau, self.tau.size
        slopes, ends = np.zeros((size, size)), np.zeros(size)
        for r in range(size):
            basis = np.poly1d([1.0])
            for s in range(size):
                if s != r:
                    basis *= np.poly1d([1.0, -tau[s]]) / (tau[r] - tau[s])
            slopes[r], ends[r] = np.polyder(basis)(tau), basis(1.0)
        return slopes, ends

    def interval(self, opti, f: ca.Function, t0, h, x_begin, control, guess) -> tuple:
        """(state at the end, [(t, s, x) at every collocation point]) of one control interval;
        `control(s)`: the control at fraction s of it; `guess(s)`: a state there (numbers)."""
        slopes, ends = self.coefficients
        n, x, points = x_begin.shape[0], x_begin, []
        for e in range(self.elements):
            xc = opti.variable(n, self.degree)
            fractions = [(e + tau) / self.elements for tau in self.tau[1:]]
            opti.set_initial(xc, np.column_stack([guess(s) for s in fractions]))
            states = ca.horzcat(x, xc)
            for j in range(1, self.degree + 1):
                s = fractions[j - 1]
                slope = states @ ca.DM(slopes[:, j])
                opti.subject_to(slope == h / self.elements * f(t0 + s * h, xc[:, j - 1],
                                                               control(s)))
                points.append((t0 + s * h, s, xc[:, j - 1]))
            x = states @ ca.DM(ends)
        return x, points
