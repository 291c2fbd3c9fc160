"""The basic constraints of the r-p formulation. Each writes ONLY phi; CasADi derives the rest.

A primitive sees one `Frame` per body its row names (position r and rotation A; ground has
constant ones), in the row's order (body_i, body_j, then any others), the primitive's vectors
(body-frame `_bar` vectors, global `c`) and the value of its driving function f (already
evaluated, symbolic in t). The table `PRIMITIVES` maps a kind to a `Primitive` (its phi
function and the vector keys it needs); `register` adds a kind (a row over two bodies, or over
three to couple them), `unregister` removes it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import casadi as ca

from casmech.core.records import record


@record
class Frame:
    """Position of the body frame origin (the CM) and rotation matrix, both global."""

    r: ca.SX
    A: ca.SX


def d_ij(fi: Frame, s_i, fj: Frame, s_j):
    """d_ij = r_j + A_j s_bar_j^Q - r_i - A_i s_bar_i^P."""
    return fj.r + fj.A @ s_j - fi.r - fi.A @ s_i


def dp1(fi: Frame, fj: Frame, v: Mapping, f):
    """a_bar_i^T A_i^T A_j a_bar_j - f(t)."""
    return (fi.A @ v["a_i"]).T @ (fj.A @ v["a_j"]) - f


def dp2(fi: Frame, fj: Frame, v: Mapping, f):
    """a_bar_i^T A_i^T d_ij - f(t)."""
    return (fi.A @ v["a_i"]).T @ d_ij(fi, v["s_i"], fj, v["s_j"]) - f


def distance(fi: Frame, fj: Frame, v: Mapping, f):
    """d_ij^T d_ij - f(t)."""
    d = d_ij(fi, v["s_i"], fj, v["s_j"])
    return d.T @ d - f


def cd(fi: Frame, fj: Frame, v: Mapping, f):
    """c^T d_ij - f(t)."""
    return v["c"].T @ d_ij(fi, v["s_i"], fj, v["s_j"]) - f


def angle(fi: Frame, fj: Frame, v: Mapping, f):
    """Rotation driver about the joint axis: sin(theta - f(t)), theta = angle of u_j from u_i.

    With u_i, v_i perpendicular to the axis on body i and u_j = u_i at angle 0 on body j,
    cos(theta) = u_i . u_j and sin(theta) = v_i . u_j, so this row equals
    (v_i . u_j) cos f - (u_i . u_j) sin f = sin(theta - f). Its derivative with respect to theta
    is cos(theta - f) = 1 at the solution: well-conditioned at every angle, unlike a bare DP1 on
    cos(theta). (The mirrored root theta = f + pi is kept away by assembly's continuation.)
    """
    u_j = fj.A @ v["u_j"]
    return (fi.A @ v["v_i"]).T @ u_j * ca.cos(f) - (fi.A @ v["u_i"]).T @ u_j * ca.sin(f)


PhiFunction = Callable[..., object]  # (*frames, vectors, f) -> phi


class Primitive(tuple):
    """(phi, vector keys): `phi(*frames, vectors, f)`, one frame per body of the row; every
    vector is a 3-vector (body frame, or global for `c`)."""

    def __new__(cls, phi: PhiFunction, keys: tuple[str, ...]):
        return super().__new__(cls, (phi, tuple(keys)))

    @property
    def phi(self) -> PhiFunction:
        return self[0]

    @property
    def keys(self) -> tuple[str, ...]:
        return self[1]


BUILT_IN = {
    "dp1": Primitive(dp1, ("a_i", "a_j")),
    "dp2": Primitive(dp2, ("a_i", "s_i", "s_j")),
    "d": Primitive(distance, ("s_i", "s_j")),
    "cd": Primitive(cd, ("c", "s_i", "s_j")),
    "angle": Primitive(angle, ("u_i", "v_i", "u_j")),
}
PRIMITIVES: dict[str, Primitive] = dict(BUILT_IN)


def register(kind: str, phi: PhiFunction, keys: tuple[str, ...]) -> None:
    """Add (or replace) a kind of constraint row: every builder reads PRIMITIVES."""
    PRIMITIVES[kind] = Primitive(phi, keys)


def unregister(kind: str) -> None:
    del PRIMITIVES[kind]


def phi(kind: str, frames, vectors: Mapping, f):
    """phi of one row of `kind` over its bodies' frames."""
    return PRIMITIVES[kind].phi(*frames, vectors, f)
