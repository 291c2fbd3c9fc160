"""ModelIR -> the symbolic constraint system: Phi and everything CasADi derives from it.

`q = [r_1..r_nb, p_1..p_nb]`. Ground is a pseudo-body with its own symbols `q_ground`
(r = 0, p = [1, 0, 0, 0] when evaluated) so that reactions ON ground come out of the same AD as
reactions on any body; every analysis function substitutes the constant ground pose.

Derived (never by hand): Phi_q, nu = -Phi_t,
gamma = -(Phi_q q_dot)_q q_dot - 2 Phi_qt q_dot - Phi_tt, and the delta-pi_bar variation matrices
Pi_bar_k = 1/2 Phi_p_k G(p_k)^T.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.core.traced_steps import traced
from casmech.core.values import constant
from casmech.elements.primitives import PRIMITIVES, ROW, Frame
from casmech.equations import body
from casmech.model.ir import GROUND_INDEX, ModelIR, PrimitiveIR

GROUND_POSE = np.array([0.0, 0, 0, 1, 0, 0, 0])


@dataclass(frozen=True)
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
        vector = self.q if vector is None else vector
        return self.q_ground[0:3] if k == GROUND_INDEX else vector[3 * k:3 * k + 3]

    def p(self, k: int, vector=None):
        vector = self.q if vector is None else vector
        if k == GROUND_INDEX:
            return self.q_ground[3:7]
        start = 3 * self.n_bodies + 4 * k
        return vector[start:start + 4]

    def frame(self, k: int) -> Frame:
        """Body k's (or ground's) position and A(p), built once: every primitive, force and
        reaction on the body shares the same expression nodes."""
        if k not in self._frames:
            self._frames[k] = Frame(self.r(k), _ROTATION(self.p(k))[0])
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


def _rotation(p):
    return (euler.rotation(p),)


def _g_transpose(p):
    return (euler.g_matrix(p).T,)


_ROTATION, _G_TRANSPOSE = traced(_rotation), traced(_g_transpose)  # per-body steps


def driver_value(prim: PrimitiveIR, t, scale=1.0):
    """f(t) of a primitive (with its constant offset); drivers are multiplied by `scale`."""
    value = prim.f.casadi(t=t) if prim.f is not None else 0.0
    if prim.is_driver:
        value = scale * value
    return value + prim.offset


def constraint_rows(ir: ModelIR, x: Coordinates, scale=1.0):
    """Phi with ground symbolic: the joint rows, then p^T p - 1 for every body."""
    rows, known = [], {}
    for prim in ir.primitives:  # each row through its kind's traced step (primitives.ROW)
        fi, fj = x.frame(prim.body_i), x.frame(prim.body_j)
        rows += ROW(fi.r, fi.A, fj.r, fj.A, _as_sx(driver_value(prim, x.t, scale), known),
                    *(_as_sx(prim.vectors[k], known) for k in PRIMITIVES[prim.kind][1]),
                    kind=prim.kind)
    rows += [body.normalization(x.p(k)) for k in range(ir.n_bodies)]
    return ca.vertcat(*rows) if rows else ca.SX(0, 1)


def _as_sx(value, known: dict):
    """A primitive's vector or driver value as SX; numbers converted once per value (`known`:
    their bytes -> SX), symbols as they are."""
    if isinstance(value, (ca.SX, ca.MX)):
        return value
    array = np.asarray(value, float)
    key = (array.shape, array.tobytes())
    if key not in known:
        known[key] = ca.SX(constant(array))
    return known[key]


def rotational_jacobian(phi_q, x: Coordinates, k: int):
    """Pi_bar of body k: 1/2 Phi_p_k G(p_k)^T (delta-pi_bar flavour of the variation, as
    body.pi_bar, with G^T a traced step), from body k's columns of Phi_q
    (docs/decisions/pi-bar-from-phi-q.md)."""
    start = 3 * x.n_bodies + 4 * k
    return 0.5 * phi_q[:, start:start + 4] @ _G_TRANSPOSE(x.p(k))[0]


@dataclass(frozen=True)
class ConstraintSystem:
    """Phi and phi_q, nu; the other parts are built when first read (a run in joint
    coordinates reads phi, phi_q and nu only)."""

    ir: ModelIR
    x: Coordinates
    phi: ca.SX  # ground substituted
    phi_with_ground: ca.SX  # ground symbolic (for reactions on ground)
    phi_q: ca.SX
    nu: ca.SX
    scale: ca.SX  # continuation parameter of the drivers (assembly)

    @cached_property
    def gamma(self) -> ca.SX:
        return gamma_of(self.phi_q, self.nu, self.x.q, self.x.t, self.x.q_dot)

    @property
    def phi_r(self) -> ca.SX:  # (m, 3 nb)
        return self.phi_q[:, :3 * self.x.n_bodies]

    @cached_property
    def pi_bar(self) -> ca.SX:  # (m, 3 nb)
        nb = self.x.n_bodies
        if not nb:
            return self.phi_r
        return ca.horzcat(*[rotational_jacobian(self.phi_q, self.x, k) for k in range(nb)])

    @cached_property
    def phi_scaled(self) -> ca.SX:
        if not any(prim.is_driver for prim in self.ir.primitives):  # scale multiplies drivers
            return self.phi
        return self.x.ground_fixed(constraint_rows(self.ir, self.x, self.scale))

    @cached_property
    def phi_q_scaled(self) -> ca.SX:
        if self.phi_scaled is self.phi:
            return self.phi_q
        return ca.jacobian(self.phi_scaled, self.x.q)


def derivatives(phi, q, t, q_dot) -> dict[str, ca.SX]:
    """Phi_q, nu, gamma of phi(t, q) by AD, for any symbols q, t, q_dot (the whole system's,
    or one row's: equations.mapped.rows)."""
    phi_q = ca.jacobian(phi, q)
    nu = -ca.jacobian(phi, t)
    return {"phi_q": phi_q, "nu": nu, "gamma": gamma_of(phi_q, nu, q, t, q_dot)}


def gamma_of(phi_q, nu, q, t, q_dot) -> ca.SX:
    """gamma = -(Phi_q q_dot)_q q_dot - 2 Phi_qt q_dot - Phi_tt (Phi_t = -nu)."""
    phi_q_qdot = phi_q @ q_dot
    return (-ca.jacobian(phi_q_qdot, q) @ q_dot - 2 * ca.jacobian(phi_q_qdot, t)
            - ca.jacobian(-nu, t))


def build_constraints(ir: ModelIR) -> ConstraintSystem:
    x = Coordinates.create(ir.n_bodies)
    phi_ground = constraint_rows(ir, x)
    phi = x.ground_fixed(phi_ground)
    return ConstraintSystem(ir, x, phi, phi_ground, ca.jacobian(phi, x.q),
                            -ca.jacobian(phi, x.t), ca.SX.sym("s"))
