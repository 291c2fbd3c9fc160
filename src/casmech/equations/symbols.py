"""The symbols of one model in body coordinates: time, q = [r_1..r_nb, p_1..p_nb], its rates,
and ground's pseudo-coordinates (r = 0, p = [1, 0, 0, 0] when evaluated), through which a force
law reads a body's frame, point or rate."""

from __future__ import annotations

from dataclasses import field

import casadi as ca

from casmech.core import euler
from casmech.core.records import record
from casmech.core.values import constant
from casmech.elements.primitives import Frame
from casmech.equations.derivatives import GROUND_POSE
from casmech.model.ir import GROUND_INDEX


@record
class Coordinates:
    """Symbols of one model: time, coordinates and their rates, ground's pseudo-coordinates."""

    t: ca.SX
    q: ca.SX
    q_dot: ca.SX
    q_ddot: ca.SX
    q_ground: ca.SX
    n_bodies: int
    _frames: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @staticmethod
    def create(n_bodies: int) -> Coordinates:
        n = 7 * n_bodies
        return Coordinates(ca.SX.sym("t"), ca.SX.sym("q", n), ca.SX.sym("q_dot", n),
                           ca.SX.sym("q_ddot", n), ca.SX.sym("q_ground", 7), n_bodies)

    def r(self, k: int, vector=None):
        """Body k's position in `vector` (default q; another: its rate of that order). Ground:
        its pseudo-coordinates in q, zero in a rate (ground is at rest)."""
        vector = self.q if vector is None else vector
        if k == GROUND_INDEX:
            return self.q_ground[0:3] if vector is self.q else ca.SX.zeros(3, 1)
        return vector[3 * k:3 * k + 3]

    def p(self, k: int, vector=None):
        """Body k's Euler parameters in `vector`, as r."""
        vector = self.q if vector is None else vector
        if k == GROUND_INDEX:
            return self.q_ground[3:7] if vector is self.q else ca.SX.zeros(4, 1)
        start = 3 * self.n_bodies + 4 * k
        return vector[start:start + 4]

    def frame(self, k: int) -> Frame:
        """Body k's (or ground's) position and A(p), built once: every force and reaction on
        the body shares the same expression nodes."""
        if k not in self._frames:
            self._frames[k] = Frame(self.r(k), euler.rotation(self.p(k)))
        return self._frames[k]

    def point(self, k: int, s_bar):
        """Global position of a point fixed in body k (ground: s_bar is already global)."""
        frame = self.frame(k)
        return frame.r + frame.A @ constant(s_bar)

    def rate(self, expr):
        """The time derivative of an expression of q along q_dot."""
        return ca.jacobian(expr, self.q) @ self.q_dot

    def ground_fixed(self, expr):
        """Substitute ground's constant pose."""
        return ca.substitute(expr, self.q_ground, ca.DM(GROUND_POSE))
