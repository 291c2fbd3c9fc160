"""The element kernels of the DAE residuals of formulations.dae (formulations.residuals sums them):
for one joint, one body, one force element, both formulations (rp, romega) and both
stabilizations (ggl: the index-2 GGL DAE; projection: the index-1 DAE). Each is an SX
Function (y, d) -> out of the element's unknowns y and data d (not differentiated), built
from the row, body and force kernels of equations.row_kernels, body_kernels and force_kernels,
with the residual's terms written once in formulations.dae_terms, element by element:

    ode:  q_dot(q, v) + Phi_q^T mu (ggl),  v_dot
    alg:  M v_dot + P^T lam - F,  then per row either (1 - w) phi - w mu and
          (1 - w) (P v - nu) - w lam (ggl), or P v_dot - gamma - w lam (projection)

with every row of P scaled by a constant s and, for ggl, every row of Phi and Phi_q by s_phi
(constants of p that the runtime sets to the inverse row norms at each start; in r-p the ode's
Phi_q^T mu uses P's own scaling, as formulations.dae does).
"""

from __future__ import annotations

import hashlib
from functools import lru_cache

import casadi as ca

from casmech.equations import body as body_terms
from casmech.equations import body_kernels, derivatives, evaluation, row_kernels
from casmech.formulations import dae_terms as terms

ROW = row_kernels.ROW  # x = [r_i, p_i, r_j, p_j]
BODY_V = {"rp": 7, "romega": 6}  # a body's velocity entries: q_dot, or [r_dot, omega_bar]


def _function(name: str, y, d, out: list) -> ca.Function:
    return ca.Function(name, [y, d], [ca.vertcat(*out)], ["y", "d"], ["out"])


def joint_data_sizes(keys) -> list[int]:
    """Vector entries of d per row (0 where the kernel bakes them)."""
    return [0 if key.values is not None else row_kernels.constraint(key).sparsity_in(1).nnz()
            for key in keys]


def n_scales(kind: str) -> int:
    """Row constants per row in d: w and s, and s_phi for ggl (formulations.terms.parameters)."""
    return 3 if kind == "ggl" else 2


@lru_cache(maxsize=512)
def joint(keys: tuple, form: str, kind: str) -> ca.Function:
    """The r rows of one joint over its bodies (x = [q_i, q_j (, ...)], v their velocities),
    every row of P scaled by its constant s (and of Phi, Phi_q by s_phi: formulations.dae).

    y = [x, v, lam (r), mu (r)] (ggl) or [x, v, v_dot, lam (r)] (projection);
    out = [Phi_q_s^T mu (x), P_s^T lam, (1 - w) phi_s - w mu (r), (1 - w) (P_s v -
    nu_s) - w lam (r)] (ggl) or [P_s^T lam, P_s v_dot - gamma_s - w lam (r)] (projection);
    d = [w, s (, s_phi) (r each), f, f', f'' of each row (3 r), each row's vectors unless
    baked]. In r-p, P is Phi_q: Phi_q_s = P_s (s) and phi_s = s_phi phi, as formulations.terms."""
    r, n_v, n_c = len(keys), BODY_V[form] * keys[0].bodies, n_scales(kind)
    width = keys[0].width
    sizes = joint_data_sizes(keys)
    d = ca.SX.sym("d", (n_c + 3) * r + sum(sizes))
    y = ca.SX.sym("y", width + n_v + (2 * r if kind == "ggl" else n_v + r))
    x, v = y[:width], y[width:width + n_v]
    w, scale = d[:r], d[r:2 * r]
    lam = y[-2 * r:-r] if kind == "ggl" else y[-r:]
    rows, start = [], (n_c + 3) * r
    for k, key in enumerate(keys):
        pattern = row_kernels.constraint(key).sparsity_in(1)
        c = ca.SX(pattern, d[start:start + sizes[k]]) if sizes[k] else ca.SX(pattern)
        f, start = d[n_c * r + 3 * k:n_c * r + 3 * k + 3], start + sizes[k]
        phi, jac, nu = row_kernels.constraint(key)(x, c, f)
        raw = row_kernels.variation(key)(x, c, f) if form == "romega" else jac
        gamma = (row_kernels.romega_gamma(key)(x, v, c, f) if form == "romega"
                 else row_kernels.gamma(key)(x, v, c, f)) if kind == "projection" else None
        rows.append((phi, jac, nu, raw, gamma))
    phi, jac, nu, raw, gamma = (ca.vertcat(*column) if column[0] is not None else None
                                for column in zip(*rows, strict=True))
    p_s = terms.scaled(raw, scale)
    if kind == "ggl":
        scale_phi, mu = d[2 * r:3 * r], y[-r:]
        phi_q_s = p_s if form == "rp" else terms.scaled(jac, scale_phi)
        parts = terms.Parts(v=v, rows=terms.Rows(p_s, lam, w, nu_s=nu * scale,
                                                 phi_s=phi * scale_phi, phi_q_s=phi_q_s,
                                                 w_phi=w, mu=mu))
    else:
        v_dot = y[width + n_v:width + 2 * n_v]
        parts = terms.Parts(v_dot=v_dot, rows=terms.Rows(p_s, lam, w, gamma_s=gamma * scale))
    out = [part for part in terms.residual(parts, kind) if part is not None]
    digest = hashlib.sha256(repr(keys).encode()).hexdigest()[:10]
    return _function(f"element_{form}_{kind}_joint_{digest}", y, d, out)


def q_dot(form: str, q, v):
    """A body's q_dot from its velocity: v (rp), [r_dot; 1/2 G^T omega_bar] (romega)."""
    return v if form == "rp" else ca.vertcat(v[:3], body_terms.p_dot(q[3:], v[3:]))


def body_constants(form: str, kind: str) -> int:
    """Row constants of the normalization row in a body's d: w, s (, s_phi) in r-p (a row of
    P); s_phi alone for romega ggl (a row of Phi only, w = 0); none for romega projection."""
    if form == "rp":
        return n_scales(kind)
    return 1 if kind == "ggl" else 0


def _mass_and_forces(form: str, pattern: tuple[bool, ...], p, rate, mass, j_flat, gravity
                     ) -> tuple:
    """M and F of one body over its velocity (rate: p_dot in rp, omega_bar in romega), from
    the per-body kernels of equations.body_kernels: blkdiag(m I, 4 G^T J G) and [m g; 8 G_dot^T
    J G_dot p] (rp), blkdiag(m I, J) and [m g; -omega~ J omega] (romega)."""
    per_body = body_kernels.kernels_for(pattern)
    if form == "rp":
        block = per_body["mass"](p, j_flat)
        torque = per_body["quadratic"](p, rate, j_flat)
    else:
        block = body_kernels.inertia_matrix(j_flat)
        torque = per_body["gyroscopic"](p, rate, j_flat)
    return ca.diagcat(mass * ca.SX.eye(3), block), ca.vertcat(mass * gravity, torque)


@lru_cache(maxsize=64)
def body(pattern: tuple[bool, ...], gravity: tuple[float, ...] | None, form: str, kind: str
         ) -> ca.Function:
    """One body, with its normalization row where the DAE has one (rp: a row of P; romega
    ggl: a row of Phi only).

    y = [q (7), v, v_dot, lam_n (rp), mu_n (ggl)]; out = [q_dot + Phi_q_s^T mu_n (7), v_dot,
    M v_dot + P_s^T lam_n - F, then the normalization row's alg entries] (formulations.dae_terms);
    F: gravity and quadratic velocity (rp) or the gyroscopic torque (romega). d = [the row's
    constants (body_constants), m, J_bar (, g when gravity is model data: None)]."""
    n_v, n_c = BODY_V[form], body_constants(form, kind)
    n_j = sum(pattern)
    y = ca.SX.sym("y", 7 + 2 * n_v + (1 if form == "rp" else 0) + (1 if kind == "ggl" else 0))
    d = ca.SX.sym("d", n_c + 1 + n_j + (3 if gravity is None else 0))
    j_flat = ca.SX(evaluation.sparse_column(pattern), d[n_c + 1:n_c + 1 + n_j])
    g = d[n_c + 1 + n_j:] if gravity is None else ca.DM(gravity)
    q, v, v_dot = y[:7], y[7:7 + n_v], y[7 + n_v:7 + 2 * n_v]
    p = q[3:]
    matrix, forces = _mass_and_forces(form, pattern, p, v[3:], d[n_c], j_flat, g)
    ode = q_dot(form, q, v)
    # the normalization row, over q (zero on r)
    phi = body_terms.normalization(p)
    norm = derivatives.of_phi(phi, p, ca.SX.sym("t"), ode[3:])
    jac = ca.horzcat(ca.SX(1, 3), norm["phi_q"])
    rows = None  # romega projection: not a row of P or of Phi
    if form == "rp":
        w, scale, lam = d[0], d[1], y[7 + 2 * n_v]
        p_s = jac * scale
        rows = terms.Rows(p_s, lam, w, gamma_s=norm["gamma"] * scale, nu_s=norm["nu"] * scale,
                          phi_s=phi * d[2] if kind == "ggl" else None, phi_q_s=p_s, w_phi=w,
                          mu=y[-1] if kind == "ggl" else None)
    elif kind == "ggl":  # a row of Phi only: w = 0
        empty = ca.SX(0, 1)
        rows = terms.Rows(ca.SX(0, n_v), empty, empty, nu_s=empty, phi_s=phi * d[0],
                          phi_q_s=jac * d[0], w_phi=0, mu=y[-1])
    parts = terms.Parts(v=v, q_dot=ode, v_dot=v_dot, mass=matrix, forces=forces, rows=rows)
    out = terms.residual(parts, kind)
    digest = "".join("1" if on else "0" for on in pattern)
    return _function(f"element_{form}_{kind}_body_{digest}", y, d,
                     [part for part in out if part is not None])


def generalized_to(form: str, x, generalized):
    """A force element's generalized force over x = [q_i (, q_j)] in the formulation's
    velocity coordinates: itself (rp), [Q_r; 1/2 G(p) Q_p] per body (romega)."""
    if form == "rp":
        return generalized
    parts = []
    for s in range(generalized.numel() // 7):
        q_s, g_s = x[7 * s:7 * s + 7], generalized[7 * s:7 * s + 7]
        parts += [g_s[:3], body_terms.moment(q_s[3:], g_s[3:])]
    return ca.vertcat(*parts)


@lru_cache(maxsize=256)
def force(kernel: ca.Function, form: str) -> ca.Function:
    """A force element's -F: y = [x (14), v of both bodies], d = [t, data, value]."""
    _, _, _, data, value = kernel.sx_in()
    n_v = BODY_V[form]
    y = ca.SX.sym("y", ROW + 2 * n_v)
    d = ca.SX.sym("d", 1 + data.nnz() + value.nnz())
    x = y[:ROW]
    x_dot = ca.vertcat(*[q_dot(form, x[7 * s:7 * s + 7], y[ROW + n_v * s:ROW + n_v * (s + 1)])
                         for s in range(2)])
    generalized = kernel(x, x_dot, d[0], ca.SX(data.sparsity(), d[1:1 + data.nnz()]),
                         ca.SX(value.sparsity(), d[1 + data.nnz():]))[0]
    parts = terms.Parts(forces=generalized_to(form, x, generalized))
    return _function(f"element_{form}_{kernel.name()}", y, d,
                     [terms.residual(parts, "projection")[2]])
