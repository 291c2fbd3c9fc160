"""The element kernels of the DAE residuals of compiler.dae (codegen.residuals sums them):
for one joint, one body, one force element, both formulations (rp, romega) and both
stabilizations (ggl: the index-2 GGL DAE; projection: the index-1 DAE). Each is an SX
Function (y, d) -> out of the element's unknowns y and data d (not differentiated), written
with the row, body and force kernels of codegen.rows, codegen.bodies and codegen.forces; the
terms are compiler.dae's, element by element:

    ode:  q_dot(q, v) + Phi_q^T mu (ggl),  v_dot
    alg:  M v_dot + P^T lam - F,  then per row either (1 - w) phi - w mu and
          (1 - w) (P v - nu) - w lam (ggl), or P v_dot - gamma - w lam (projection)

with every row of P scaled by a constant s and, for ggl, every row of Phi and Phi_q by s_phi
(constants of p that the runtime sets to the inverse row norms at each start; in r-p the ode's
Phi_q^T mu uses P's own scaling, as compiler.dae does).
"""

from __future__ import annotations

import hashlib
from functools import lru_cache

import casadi as ca

from casmech.codegen import bodies
from casmech.codegen import rows as row_kernels
from casmech.geometry import euler

ROW = row_kernels.ROW  # x = [r_i, p_i, r_j, p_j]
V_WIDTH = {"rp": 14, "romega": 12}  # a joint's velocity entries: q_dot, or [r_dot, omega_bar]
BODY_V = {"rp": 7, "romega": 6}


def _function(name: str, y, d, out: list) -> ca.Function:
    return ca.Function(name, [y, d], [ca.vertcat(*out)], ["y", "d"], ["out"])


def joint_data_sizes(keys) -> list[int]:
    """Vector entries of d per row (0 where the kernel bakes them)."""
    return [0 if key.values is not None else row_kernels.constraint(key).sparsity_in(1).nnz()
            for key in keys]


def n_scales(kind: str) -> int:
    """Row constants per row in d: w and s, and s_phi for ggl (compiler.dae.parameters)."""
    return 3 if kind == "ggl" else 2


@lru_cache(maxsize=512)
def joint(keys: tuple, form: str, kind: str) -> ca.Function:
    """The r rows of one joint between bodies i and j (x = [q_i, q_j], v their velocities),
    every row of P scaled by its constant s (and of Phi, Phi_q by s_phi: compiler.dae).

    y = [x (14), v, lam (r), mu (r)] (ggl) or [x, v, v_dot, lam (r)] (projection);
    out = [sum Phi_q_s^T mu (14), sum P_s^T lam, (1 - w) phi_s - w mu (r), (1 - w) (P_s v -
    nu_s) - w lam (r)] (ggl) or [sum P_s^T lam, P_s v_dot - gamma_s - w lam (r)] (projection);
    d = [w, s (, s_phi) (r each), f, f', f'' of each row (3 r), each row's vectors unless
    baked]. In r-p, P is Phi_q: Phi_q_s = P_s (s) and phi_s = s_phi phi, as compiler.dae."""
    r, n_v, n_c = len(keys), V_WIDTH[form], n_scales(kind)
    sizes = joint_data_sizes(keys)
    d = ca.SX.sym("d", (n_c + 3) * r + sum(sizes))
    y = ca.SX.sym("y", ROW + n_v + (2 * r if kind == "ggl" else n_v + r))
    x, v = y[:ROW], y[ROW:ROW + n_v]
    w, scale, scale_phi = d[:r], d[r:2 * r], d[2 * r:3 * r] if kind == "ggl" else None
    lam = y[-2 * r:-r] if kind == "ggl" else y[-r:]
    sum_mu, sum_lam, first, second = ca.SX(ROW, 1), ca.SX(n_v, 1), [], []
    start = (n_c + 3) * r
    for k, key in enumerate(keys):
        pattern = row_kernels.constraint(key).sparsity_in(1)
        c = ca.SX(pattern, d[start:start + sizes[k]]) if sizes[k] else ca.SX(pattern)
        f, start = d[n_c * r + 3 * k:n_c * r + 3 * k + 3], start + sizes[k]
        phi, jac, nu = row_kernels.constraint(key)(x, c, f)
        raw = row_kernels.variation(key)(x, c, f) if form == "romega" else jac
        p = raw * scale[k]
        if kind == "ggl":
            mu = y[-r + k]
            sum_mu += (p if form == "rp" else jac * scale_phi[k]).T * mu
            first.append((1 - w[k]) * phi * scale_phi[k] - w[k] * mu)
            second.append((1 - w[k]) * (p @ v - nu * scale[k]) - w[k] * lam[k])
        else:
            gamma = row_kernels.romega_gamma(key)(x, v, c, f) if form == "romega" \
                else row_kernels.gamma(key)(x, v, c, f)
            first.append(p @ y[ROW + n_v:ROW + 2 * n_v] - gamma * scale[k] - w[k] * lam[k])
        sum_lam += p.T * lam[k]
    out = [sum_mu, sum_lam, *first, *second] if kind == "ggl" else [sum_lam, *first]
    digest = hashlib.sha256(repr(keys).encode()).hexdigest()[:10]
    return _function(f"element_{form}_{kind}_joint_{digest}", y, d, out)


def q_dot(form: str, q, v):
    """A body's q_dot from its velocity: v (rp), [r_dot; 1/2 G^T omega_bar] (romega)."""
    return v if form == "rp" else ca.vertcat(v[:3], 0.5 * euler.g_matrix(q[3:]).T @ v[3:])


def body_constants(form: str, kind: str) -> int:
    """Row constants of the normalization row in a body's d: w, s (, s_phi) in r-p (a row of
    P); s_phi alone for romega ggl (a row of Phi only, w = 0); none for romega projection."""
    if form == "rp":
        return n_scales(kind)
    return 1 if kind == "ggl" else 0


@lru_cache(maxsize=64)
def body(pattern: tuple[bool, ...], gravity: tuple[float, ...], form: str, kind: str
         ) -> ca.Function:
    """One body, with its normalization row where the DAE has one (rp: a row of P; romega
    ggl: a row of Phi only).

    y = [q (7), v, v_dot, lam_n (rp), mu_n (ggl)]; out = [q_dot + Phi_q_s^T mu_n (7), v_dot,
    M v_dot - F + P_s^T lam_n, then the normalization row's alg entries]; F: gravity and
    quadratic velocity (rp) or the gyroscopic torque (romega). d = [the row's constants
    (body_constants), m, J_bar]."""
    kernels = bodies._kernels(pattern, gravity)
    n_v, rp, n_c = BODY_V[form], form == "rp", body_constants(form, kind)
    y = ca.SX.sym("y", 7 + 2 * n_v + (1 if rp else 0) + (1 if kind == "ggl" else 0))
    d = ca.SX.sym("d", n_c + 1 + sum(pattern))
    mass, inertia = d[n_c], ca.SX(kernels["mass"].sparsity_in(1), d[n_c + 1:])
    q, v, v_dot = y[:7], y[7:7 + n_v], y[7 + n_v:7 + 2 * n_v]
    p, zero = q[3:], ca.SX(3, 1)
    translation = mass * v_dot[:3] - mass * ca.DM(gravity)
    if rp:
        rotation = kernels["mass"](p, inertia) @ v_dot[3:] - kernels["quadratic"](
            p, v[3:], inertia)
    else:
        dense = ca.reshape(ca.densify(inertia), 3, 3)
        rotation = dense @ v_dot[3:] - kernels["gyroscopic"](p, v[3:], inertia)
    alg = ca.vertcat(translation, rotation)
    ode = [q_dot(form, q, v), v_dot]
    phi, jac, nu = row_kernels.normalization()[0](p)
    rows = []
    if rp:
        w, scale, lam = d[0], d[1], y[7 + 2 * n_v]
        jac_s = jac * scale
        if kind == "ggl":
            mu = y[-1]
            rows = [(1 - w) * phi * d[2] - w * mu, (1 - w) * (jac_s @ v[3:] - nu * scale)
                    - w * lam]
            ode[0] += ca.vertcat(zero, jac_s.T * mu)
        else:
            gamma = row_kernels.normalization()[1](p, v[3:])
            rows = [jac_s @ v_dot[3:] - gamma * scale - w * lam]
        alg += ca.vertcat(zero, jac_s.T * lam)
    elif kind == "ggl":
        rows = [phi * d[0]]
        ode[0] += ca.vertcat(zero, (jac * d[0]).T * y[-1])
    digest = "".join("1" if on else "0" for on in pattern)
    return _function(f"element_{form}_{kind}_body_{digest}", y, d, [*ode, alg, *rows])


def generalized_to(form: str, x, generalized):
    """A force element's generalized force over x = [q_i (, q_j)] in the formulation's
    velocity coordinates: itself (rp), [Q_r; 1/2 G(p) Q_p] per body (romega)."""
    if form == "rp":
        return generalized
    parts = []
    for s in range(generalized.numel() // 7):
        q_s, g_s = x[7 * s:7 * s + 7], generalized[7 * s:7 * s + 7]
        parts += [g_s[:3], 0.5 * euler.g_matrix(q_s[3:]) @ g_s[3:]]
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
    return _function(f"element_{form}_{kernel.name()}", y, d,
                     [-generalized_to(form, x, generalized)])
