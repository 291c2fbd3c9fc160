"""One SX kernel per kind of constraint row: everything a row of Phi gives, for ONE row.

A row of Phi depends only on the bodies it names, x = [r_1, p_1, r_2, p_2, ...] (7 per body,
in the row's order: body_i, body_j, then any others), on its constant vectors and on its
driving function f. Rows share a kernel when they share a `RowKey`: the primitive kind, how
many bodies it reads and which of them is ground, which of its vector entries are non-zero, how
f depends on time, and (when baked) the vectors' values. Baked vectors are constants in the
kernel, so its SX simplifies as far as the numbers allow, down to the second derivatives.
Otherwise the vectors are a kernel INPUT (an SX symbol with the sparsity of the non-zero
entries), so rows of one kind with different geometry share code: every zero still simplifies,
but products of non-zero constants that cancel do not, which leaves a few structural entries
(numerically 0) in some Jacobians. equations.rows bakes while a model has few distinct
geometries (BAKE_LIMIT) and its numbers are numbers. Ground's pose is a constant inside the
kernel, except for reactions, which differentiate with respect to ground's pseudo-coordinates.

Time enters through f's Taylor coefficients [f, f', f''] at the instant (computed outside the
kernel, see `taylor`), so nu and both gammas are exact.

Every derivative is CasADi's (equations.derivatives): phi_q, nu, gamma; [Phi_r, Pi_bar]; the
r-omega gamma_hat; a row's reaction.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache

import casadi as ca

from casmech.core import euler
from casmech.core.records import record
from casmech.elements.forces.terms import at
from casmech.elements.primitives import PRIMITIVES, Frame
from casmech.equations import body, derivatives, evaluation
from casmech.model.ir import GROUND_INDEX, PrimitiveIR

BODY = 7  # [r, p] of one body in x
FRAME = 12  # [r, A (column-major)] of one body's frame
V_BODY = 6  # [r_dot, omega_bar] of one body in v
ROW = 2 * BODY  # x of a row over two bodies: [r_i, p_i, r_j, p_j]
V_ROW = 2 * V_BODY
SIDES = "ijklmnop"  # the row's bodies in order: body_i, body_j, then the others
ZERO, CONSTANT, TIME = "zero", "constant", "time"  # how f depends on t


@record
class RowKey:
    """What makes two constraint rows share one kernel: kind, ground sides, vector pattern,
    driving function class, baked values, bodies read."""

    kind: str
    ground: str | None  # the sides (SIDES) that are ground, or None
    pattern: tuple[bool, ...]  # which entries of the stacked vectors are non-zero
    f_class: str  # ZERO (f = 0), CONSTANT (f = f0), TIME (Taylor coefficients)
    values: tuple[float, ...] | None = None  # the vectors as constants (baked), else an input
    bodies: int = 2  # bodies the row reads

    def __repr__(self) -> str:
        """The kernels' C names are digests of this (the number of bodies shows when it is not
        two)."""
        extra = "" if self.bodies == 2 else f", bodies={self.bodies}"
        return (f"RowKey(kind={self.kind!r}, ground={self.ground!r}, pattern={self.pattern!r}, "
                f"f_class={self.f_class!r}, values={self.values!r}{extra})")

    @property
    def width(self) -> int:
        """Entries of x (7 per body)."""
        return BODY * self.bodies

    @property
    def v_width(self) -> int:
        """Entries of the r-omega velocity v (6 per body)."""
        return V_BODY * self.bodies


def f_constant(prim: PrimitiveIR):
    """f + offset when it does not depend on time (drivers unscaled; an SX of the model data
    for a symbolic IR), else None."""
    if prim.f is None:
        return prim.offset
    if prim.f.expr.is_constant:
        value = prim.f.casadi(t=0.0) + prim.offset
        return value if isinstance(value, ca.SX) and not value.is_constant() else float(value)
    return None


def f_class(prim: PrimitiveIR) -> str:
    value = f_constant(prim)
    return TIME if value is None else ZERO if evaluation.is_zero(value) else CONSTANT


def vectors_of(prim: PrimitiveIR) -> list:
    """The row's vectors stacked in its primitive's key order (numbers or SX entries)."""
    return [v for k in PRIMITIVES[prim.kind].keys for v in evaluation.entries(prim.vectors[k])]


def key_of(prim: PrimitiveIR, baked: bool = False) -> RowKey:
    sides = "".join(SIDES[s] for s, b in enumerate(prim.bodies) if b == GROUND_INDEX)
    vectors = vectors_of(prim)
    return RowKey(prim.kind, sides or None, tuple(not evaluation.is_zero(v) for v in vectors),
                  f_class(prim), tuple(float(v) for v in vectors) if baked else None,
                  len(prim.bodies))


def driver_value(prim: PrimitiveIR, t, scale=1.0):
    """f(t) of a primitive (with its constant offset); drivers are multiplied by `scale`."""
    value = prim.f.casadi(t=t) if prim.f is not None else 0.0
    if prim.is_driver:
        value = scale * value
    return value + prim.offset


def taylor(prim: PrimitiveIR, t, scale, ev: evaluation.Evaluation):
    """[f, f', f''] at t (the SX of f inlined: no call node per row)."""
    tt, ss = ca.SX.sym("t"), ca.SX.sym("s")
    f = ca.SX(driver_value(prim, tt, ss))
    first = ca.jacobian(f, tt)
    return ev.apply([tt, ss], [ca.vertcat(f, first, ca.jacobian(first, tt))], [t, scale])[0]


def taylor_or_constant(prim: PrimitiveIR, key: RowKey, t, ev: evaluation.Evaluation):
    """[f, f', f''] of a row at t: its Taylor coefficients when f depends on time."""
    if key.f_class == TIME:
        return taylor(prim, t, 1.0, ev)
    value = f_constant(prim)
    return ev.constant(ca.vertcat(value, 0.0, 0.0)) if isinstance(value, ca.SX) \
        else ca.DM([value, 0.0, 0.0])


class _Row:
    """The symbols and frames of one row kernel."""

    def __init__(self, key: RowKey, symbolic_ground: bool = False):
        self.key = key
        self.x = ca.SX.sym("x", key.width)
        self.c = ca.SX.sym("c", evaluation.sparse_column(key.pattern))
        self.f = ca.SX.sym("f", 3)
        self.tau = ca.SX.sym("tau")  # time from the instant
        ground = "" if symbolic_ground else key.ground or ""
        self.halves = [self._half(self.x[BODY * s:BODY * s + BODY], SIDES[s] in ground)
                       for s in range(key.bodies)]

    @staticmethod
    def _half(x, is_ground: bool):
        return (ca.SX(ca.DM(derivatives.GROUND_POSE[:3])),
                ca.SX(ca.DM(derivatives.GROUND_POSE[3:]))) if is_ground else (x[0:3], x[3:7])

    def frames(self) -> list[Frame]:
        return [Frame(r, euler.rotation(p)) for r, p in self.halves]

    def given_frames(self, frames, symbolic_ground: bool) -> list[Frame]:
        """The frames of an input [r, A] per body (ground's constant unless symbolic)."""
        ground = "" if symbolic_ground else self.key.ground or ""
        out = []
        for s in range(self.key.bodies):
            if SIDES[s] in ground:
                out.append(Frame(ca.SX(ca.DM(derivatives.GROUND_POSE[:3])), ca.SX.eye(3)))
            else:
                block = frames[FRAME * s:FRAME * s + FRAME]
                out.append(Frame(block[:3], ca.reshape(block[3:], 3, 3)))
        return out

    def f_of_tau(self):
        if self.key.f_class == ZERO:
            return 0.0
        if self.key.f_class == CONSTANT:
            return self.f[0]
        return self.f[0] + self.f[1] * self.tau + self.f[2] * self.tau**2 / 2

    def phi(self, frames: list[Frame] | None = None):
        keys = PRIMITIVES[self.key.kind].keys
        dense = ca.densify(self.c) if self.key.values is None else ca.SX(ca.DM(self.key.values))
        vectors = {k: dense[3 * n:3 * n + 3] for n, k in enumerate(keys)}
        return PRIMITIVES[self.key.kind].phi(*(frames or self.frames()), vectors,
                                             self.f_of_tau())

    def at_instant(self, *expressions):
        return [ca.substitute(e, self.tau, 0) for e in expressions]

    def derivatives(self, phi, x_dot=None) -> dict:
        """Phi_q (1 x width), nu and (given x_dot) gamma of the row."""
        return derivatives.of_phi(phi, self.x, self.tau,
                                  ca.SX(self.key.width, 1) if x_dot is None else x_dot)

    def romega_jacobian(self, phi):
        """[Phi_r, Pi_bar] of each body in turn (1 x 6 per body)."""
        jac = ca.jacobian(phi, self.x)
        parts = []
        for s, (_, p) in enumerate(self.halves):
            parts += [jac[:, BODY * s:BODY * s + 3],
                      body.pi_bar(jac[:, BODY * s + 3:BODY * s + 7], p)]
        return ca.horzcat(*parts)


@lru_cache(maxsize=512)
def phi_of_frames(key: RowKey, symbolic_ground: bool = False) -> ca.Function:
    """(frames, c, f) -> phi of one row at the instant over its bodies' frames [r, A] (FRAME
    per body, A column by column: computed once per body by the inline evaluation); with
    symbolic_ground, ground's frame is read like a body's (the inline evaluation's reactions
    differentiate with respect to its pose)."""
    row = _Row(key)
    frames = ca.SX.sym("frames", FRAME * key.bodies)
    value = row.phi(row.given_frames(frames, symbolic_ground))
    return ca.Function(f"phi_{_name(key)}", [frames, row.c, row.f], row.at_instant(value),
                       ["frames", "c", "f"], ["phi"])


@lru_cache(maxsize=256)
def constraint(key: RowKey) -> ca.Function:
    """(x, c, f) -> (phi, jac [1 x width], nu) of one row at the instant."""
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
    x_dot = ca.SX.sym("x_dot", key.width)
    value = row.derivatives(row.phi(), x_dot)["gamma"]
    return ca.Function(f"gamma_{_name(key)}", [row.x, x_dot, row.c, row.f],
                       row.at_instant(value), ["x", "x_dot", "c", "f"], ["gamma"])


@lru_cache(maxsize=256)
def variation(key: RowKey) -> ca.Function:
    """(x, c, f) -> [Phi_r, Pi_bar] of each body (1 x 6 per body), Pi_bar = 1/2 Phi_p G^T."""
    row = _Row(key)
    return ca.Function(f"variation_{_name(key)}", [row.x, row.c, row.f],
                       row.at_instant(row.romega_jacobian(row.phi())), ["x", "c", "f"],
                       ["jac"])


@lru_cache(maxsize=256)
def romega_gamma(key: RowKey) -> ca.Function:
    """(x, v, c, f) -> gamma_hat = -d/dt([Phi_r, Pi_bar] v - nu) along q_dot(q, v)
    (equations.derivatives.gamma_hat), v = [r_dot, omega_bar] of each body."""
    row = _Row(key)
    v = ca.SX.sym("v", key.v_width)
    phi = row.phi()
    x_dot = ca.vertcat(*[ca.vertcat(v[V_BODY * s:V_BODY * s + 3],
                                    body.p_dot(row.x[BODY * s + 3:BODY * s + 7],
                                               v[V_BODY * s + 3:V_BODY * s + 6]))
                         for s in range(key.bodies)])
    value = derivatives.gamma_hat(row.romega_jacobian(phi), row.derivatives(phi)["nu"], v,
                                  row.x, x_dot, row.tau)
    return ca.Function(f"romega_gamma_{_name(key)}", [row.x, v, row.c, row.f],
                       row.at_instant(value), ["x", "v", "c", "f"], ["gamma"])


@lru_cache(maxsize=256)
def reaction(key: RowKey) -> ca.Function:
    """(x, c, f, lam, s) -> (force, torque) of one row's multiplier ON body j, the torque
    about body i's point s (derivatives.reaction): ground symbolic, so the reaction on ground
    comes from the same AD."""
    row = _Row(key, symbolic_ground=True)
    lam, s = ca.SX.sym("lam"), ca.SX.sym("s", 3)
    phi = row.at_instant(row.phi())[0]
    frame_i = row.frames()[0]
    r_j, p_j = row.halves[1]
    force, torque = derivatives.reaction(phi, lam, r_j, p_j, at(frame_i, s))
    return ca.Function(f"reaction_{_name(key)}", [row.x, row.c, row.f, lam, s],
                       [force, torque], ["x", "c", "f", "lam", "s"], ["force", "torque"])


def _name(key: RowKey) -> str:
    """A C identifier unique to the key (deterministic: the generated code is reproducible)."""
    digest = hashlib.sha256(repr(key).encode()).hexdigest()[:10]
    return f"{key.kind}_{key.ground or 'n'}_{key.f_class}_{digest}"


@lru_cache(maxsize=256)
def joint_reaction(keys: tuple) -> ca.Function:
    """(x, c, f, lam, s) -> (force, torque) of one joint's rows together (x: the two bodies';
    c, f, lam: every row's, stacked): the sum of their `reaction`, the terms the rows share
    (the bodies' rotations) computed once."""
    rows = [reaction(key) for key in keys]
    c = ca.SX.sym("c", sum(r.nnz_in(1) for r in rows))
    f, lam, s = ca.SX.sym("f", 3 * len(keys)), ca.SX.sym("lam", len(keys)), ca.SX.sym("s", 3)
    x = ca.SX.sym("x", keys[0].width)
    force, torque, start = ca.SX(3, 1), ca.SX(3, 1), 0
    for k, row in enumerate(rows):
        pattern = row.sparsity_in(1)
        f_k, t_k = row(x, ca.SX(pattern, c[start:start + pattern.nnz()]), f[3 * k:3 * k + 3],
                       lam[k], s)
        force, torque, start = force + f_k, torque + t_k, start + pattern.nnz()
    digest = hashlib.sha256(repr(keys).encode()).hexdigest()[:10]
    return ca.Function(f"joint_reaction_{digest}", [x, c, f, lam, s], [force, torque],
                       ["x", "c", "f", "lam", "s"], ["force", "torque"], {"cse": True})


@lru_cache(maxsize=1)
def normalization() -> tuple[ca.Function, ca.Function, ca.Function]:
    """p^T p - 1 of one body: (p) -> (phi, jac [1 x 4], nu); (p, p_dot) -> gamma;
    (p) -> Pi_bar (1 x 3: 1/2 Phi_p G^T, zero in value)."""
    p, p_dot = ca.SX.sym("p", 4), ca.SX.sym("p_dot", 4)
    phi = body.normalization(p)
    derived = derivatives.of_phi(phi, p, ca.SX.sym("t"), p_dot)
    return (ca.Function("normalization", [p], [phi, derived["phi_q"], derived["nu"]]),
            ca.Function("normalization_gamma", [p, p_dot], [derived["gamma"]]),
            ca.Function("normalization_pi_bar", [p], [body.pi_bar(derived["phi_q"], p)]))
