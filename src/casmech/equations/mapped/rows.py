"""One SX kernel per kind of constraint row: everything a row of Phi gives, for ONE row.

A row of Phi depends only on its two bodies, x = [r_i, p_i, r_j, p_j] (14), on its constant
vectors and on its driving function f. Rows share a kernel when they share a `RowKey`: the
primitive kind, which side (if any) is ground, which of its vector entries are non-zero, how f
depends on time, and (when baked) the vectors' values. Baked vectors are constants in the
kernel, so the SX simplifies exactly as the unrolled expression (equations.assemble) does: the
same sparsity, down to the second derivatives. Otherwise the vectors are a kernel INPUT (an SX
symbol with the sparsity of the non-zero entries), so rows of one kind with different geometry
share code: every zero still simplifies, but products of non-zero constants that cancel in the
unrolled expression do not, which leaves a few structural entries (numerically 0) in some
Jacobians. equations.mapped.kernels bakes while a model has few distinct geometries (BAKE_LIMIT).
Ground's pose is a constant inside the kernel (as the unrolled functions substitute it),
except for reactions, which differentiate with respect to ground's pseudo-coordinates.

Time enters through f's Taylor coefficients [f, f', f''] at the instant (computed outside the
kernel, see `taylor`), so nu and both gammas are exact.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.elements.forces.terms import at
from casmech.elements.primitives import PRIMITIVES, Frame
from casmech.equations import body, eom, romega
from casmech.equations.assemble import GROUND_POSE, derivatives, driver_value
from casmech.model.ir import GROUND_INDEX, PrimitiveIR

ROW = 14  # x = [r_i, p_i, r_j, p_j]
V_ROW = 12  # v = [r_dot_i, omega_bar_i, r_dot_j, omega_bar_j]
ZERO, CONSTANT, TIME = "zero", "constant", "time"  # how f depends on t


@dataclass(frozen=True)
class RowKey:
    kind: str
    ground: str | None  # "i", "j" or None: the side that is ground
    pattern: tuple[bool, ...]  # which entries of the stacked vectors are non-zero
    f_class: str  # ZERO (f = 0), CONSTANT (f = f0), TIME (Taylor coefficients)
    values: tuple[float, ...] | None = None  # the vectors as constants (baked), else an input


def f_constant(prim: PrimitiveIR) -> float | None:
    """f + offset when it does not depend on time (drivers unscaled), else None."""
    if prim.f is None:
        return float(prim.offset)
    if prim.f.expr.is_constant:
        return prim.f.value(t=0.0) + float(prim.offset)
    return None


def f_class(prim: PrimitiveIR) -> str:
    value = f_constant(prim)
    return TIME if value is None else ZERO if value == 0.0 else CONSTANT


def vectors_of(prim: PrimitiveIR) -> np.ndarray:
    return np.concatenate([np.asarray(prim.vectors[k], float).ravel()
                           for k in PRIMITIVES[prim.kind][1]])


def key_of(prim: PrimitiveIR, baked: bool = False) -> RowKey:
    ground = "i" if prim.body_i == GROUND_INDEX else "j" if prim.body_j == GROUND_INDEX else None
    vectors = vectors_of(prim)
    return RowKey(prim.kind, ground, tuple(bool(v != 0) for v in vectors), f_class(prim),
                  tuple(float(v) for v in vectors) if baked else None)


def taylor(prim: PrimitiveIR, t, scale=1.0):
    """[f, f', f''] at t (an MX expression, the SX of f inlined: no call node per row)."""
    tt, ss = ca.SX.sym("t"), ca.SX.sym("s")
    f = ca.SX(driver_value(prim, tt, ss))
    first = ca.jacobian(f, tt)
    of = ca.Function("f", [tt, ss], [ca.vertcat(f, first, ca.jacobian(first, tt))])
    return of.call([t, scale], True, False)[0]


class _Row:
    """The symbols and frames of one row kernel."""

    def __init__(self, key: RowKey, symbolic_ground: bool = False):
        self.key = key
        self.x = ca.SX.sym("x", ROW)
        self.c = ca.SX.sym("c", ca.Sparsity.triplet(len(key.pattern), 1, [
            k for k, nz in enumerate(key.pattern) if nz], [0] * sum(key.pattern)))
        self.f = ca.SX.sym("f", 3)
        self.tau = ca.SX.sym("tau")  # time from the instant
        ground = None if symbolic_ground else key.ground
        self.halves = [self._half(self.x[7 * s:7 * s + 7], side == ground)
                       for s, side in enumerate("ij")]

    @staticmethod
    def _half(x, is_ground: bool):
        return (ca.SX(ca.DM(GROUND_POSE[:3])), ca.SX(ca.DM(GROUND_POSE[3:]))) if is_ground \
            else (x[0:3], x[3:7])

    def frames(self) -> list[Frame]:
        return [Frame(r, euler.rotation(p)) for r, p in self.halves]

    def f_of_tau(self):
        if self.key.f_class == ZERO:
            return 0.0
        if self.key.f_class == CONSTANT:
            return self.f[0]
        return self.f[0] + self.f[1] * self.tau + self.f[2] * self.tau**2 / 2

    def phi(self):
        kind = self.key.kind
        function, keys = PRIMITIVES[kind]
        dense = ca.densify(self.c) if self.key.values is None else ca.SX(ca.DM(self.key.values))
        vectors = {k: dense[3 * n:3 * n + 3] for n, k in enumerate(keys)}
        return function(*self.frames(), vectors, self.f_of_tau())

    def at_instant(self, *expressions):
        return [ca.substitute(e, self.tau, 0) for e in expressions]

    def derivatives(self, phi, x_dot=None) -> dict:
        """Phi_q (1 x 14), nu and (given x_dot) gamma of the row (equations.assemble)."""
        return derivatives(phi, self.x, self.tau, ca.SX(ROW, 1) if x_dot is None else x_dot)

    def romega_jacobian(self, phi):
        """[Phi_r_i, Pi_bar_i, Phi_r_j, Pi_bar_j] of the row (1 x 12)."""
        jac = ca.jacobian(phi, self.x)
        parts = []
        for s, (_, p) in enumerate(self.halves):
            parts += [jac[:, 7 * s:7 * s + 3], body.pi_bar(jac[:, 7 * s + 3:7 * s + 7], p)]
        return ca.horzcat(*parts)


@lru_cache(maxsize=256)
def constraint(key: RowKey) -> ca.Function:
    """(x, c, f) -> (phi, jac [1 x 14], nu) of one row at the instant."""
    row = _Row(key)
    phi = row.phi()
    derived = row.derivatives(phi)
    out = row.at_instant(phi, derived["phi_q"], derived["nu"])
    return ca.Function(f"row_{_name(key)}", [row.x, row.c, row.f], out,
                       ["x", "c", "f"], ["phi", "jac", "nu"])


@lru_cache(maxsize=256)
def gamma(key: RowKey) -> ca.Function:
    """(x, x_dot, c, f) -> gamma = -(Phi_q q_dot)_q q_dot - 2 Phi_qt q_dot - Phi_tt."""
    row = _Row(key)
    x_dot = ca.SX.sym("x_dot", ROW)
    value = row.derivatives(row.phi(), x_dot)["gamma"]
    return ca.Function(f"gamma_{_name(key)}", [row.x, x_dot, row.c, row.f],
                       row.at_instant(value), ["x", "x_dot", "c", "f"], ["gamma"])


@lru_cache(maxsize=256)
def variation(key: RowKey) -> ca.Function:
    """(x, c, f) -> [Phi_r_i, Pi_bar_i, Phi_r_j, Pi_bar_j] (1 x 12), Pi_bar = 1/2 Phi_p G^T."""
    row = _Row(key)
    return ca.Function(f"variation_{_name(key)}", [row.x, row.c, row.f],
                       row.at_instant(row.romega_jacobian(row.phi())), ["x", "c", "f"],
                       ["jac"])


@lru_cache(maxsize=256)
def romega_gamma(key: RowKey) -> ca.Function:
    """(x, v, c, f) -> gamma_hat = -d/dt([Phi_r, Pi_bar] v - nu) along q_dot(q, v)
    (equations.romega), v = [r_dot_i, omega_bar_i, r_dot_j, omega_bar_j]."""
    row = _Row(key)
    v = ca.SX.sym("v", V_ROW)
    phi = row.phi()
    x_dot = ca.vertcat(*[ca.vertcat(v[6 * s:6 * s + 3],
                                    body.p_dot(row.x[7 * s + 3:7 * s + 7], v[6 * s + 3:6 * s + 6]))
                         for s in range(2)])
    value = romega.gamma_hat(row.romega_jacobian(phi), row.derivatives(phi)["nu"], v, row.x,
                             x_dot, row.tau)
    return ca.Function(f"romega_gamma_{_name(key)}", [row.x, v, row.c, row.f],
                       row.at_instant(value), ["x", "v", "c", "f"], ["gamma"])


@lru_cache(maxsize=256)
def reaction(key: RowKey) -> ca.Function:
    """(x, c, f, lam, s) -> (force, torque) of one row's multiplier ON body j, the torque
    about body i's point s (equations.eom.reactions, whose sum over a joint's rows this is):
    ground symbolic, so the reaction on ground comes from the same AD."""
    row = _Row(key, symbolic_ground=True)
    lam, s = ca.SX.sym("lam"), ca.SX.sym("s", 3)
    phi = row.at_instant(row.phi())[0]
    frame_i, _ = row.frames()
    r_j, p_j = row.halves[1]
    force, torque = eom.reaction(phi, lam, r_j, p_j, at(frame_i, s))
    return ca.Function(f"reaction_{_name(key)}", [row.x, row.c, row.f, lam, s],
                       [force, torque], ["x", "c", "f", "lam", "s"], ["force", "torque"])


def _name(key: RowKey) -> str:
    """A C identifier unique to the key (deterministic: the generated code is reproducible)."""
    digest = hashlib.sha256(repr(key).encode()).hexdigest()[:10]
    return f"{key.kind}_{key.ground or 'n'}_{key.f_class}_{digest}"


@lru_cache(maxsize=1)
def normalization() -> tuple[ca.Function, ca.Function, ca.Function]:
    """p^T p - 1 of one body: (p) -> (phi, jac [1 x 4], nu); (p, p_dot) -> gamma;
    (p) -> Pi_bar (1 x 3: 1/2 Phi_p G^T, zero in value, as in the unrolled functions)."""
    p, p_dot = ca.SX.sym("p", 4), ca.SX.sym("p_dot", 4)
    phi = body.normalization(p)
    derived = derivatives(phi, p, ca.SX.sym("t"), p_dot)
    return (ca.Function("normalization", [p], [phi, derived["phi_q"], derived["nu"]]),
            ca.Function("normalization_gamma", [p, p_dot], [derived["gamma"]]),
            ca.Function("normalization_pi_bar", [p], [body.pi_bar(derived["phi_q"], p)]))
