"""The load part of joint friction in a prescribed motion (kinematics, inverse dynamics;
docs/forces.md#joint-friction).

The prescribed step (formulations/prescribed.py) solves Phi_q^T lam0 = Q - M q_ddot with each
friction's law without its load part, f0 = -sign(s_dot) Tc - c s_dot. The load part
-sign(s_dot) mu L adds the generalized force -d_j g_j s_j_q^T (d_j = sign(s_dot_j), g_j =
mu_j L_j) to Q, so with lam1_j the minimum-norm solution of Phi_q^T lam1_j = s_j_q^T (the
same QR as the step's),

    lam = lam0 - sum_j d_j g_j lam1_j,

and, the reactions being linear in lam, the load vector of joint i is n0_i - sum_j d_j g_j n1_ij
(n0_i of lam0, n1_ij of lam1_j: equations/friction_load.py). The loads g_i = mu_i |n_i| are
that system's solution (friction_load.coupled: one joint's the quadratic's root, several by
Newton's method), so the multipliers and the frictions agree exactly. At s_dot = 0 the sign is
0: no friction at rest, as the sliding law says.
"""

from __future__ import annotations

import casadi as ca

from casmech.equations import friction, friction_load
from casmech.equations.symbols import Coordinates


def elements(ir) -> list:
    """The joint frictions with a sliding load part (`mu` not 0)."""
    return [e for e in ir.limits if e.type in friction.COORDINATE
            and not (isinstance(e.params["mu"], (int, float)) and e.params["mu"] == 0)]


def correction(functions, loaded: list) -> ca.Function:
    """(t, q, q_dot, lam0) -> (lam, f, loads): the multipliers with the load parts of the
    frictions `loaded` (the step's lam0 without them), each one's friction force f (the
    results column `<joint>.friction`), and friction_load.sliding's outputs for them (the
    load parts g, the system's largest residual, A_ij = mu_i |n1_ij|), which the runtime
    checks as a dynamics run does (unique: A's spectral radius below 1; solved)."""
    from casmech.numerics.sparse_qr import sparse_qr

    nb = functions.ir.n_bodies
    x = Coordinates.create(nb)
    t, q, q_dot = x.t, x.q, x.q_dot
    lam0 = ca.SX.sym("lam0", functions.n_rows)
    phi_q = functions["phi_q"]
    qr = sparse_qr(phi_q.sparsity_out(0), "phi_q_qr")
    factors = qr.factor(x.ground_fixed(phi_q(t, q)))[:3]
    laws = [friction.law(e, x) for e in loaded]
    units = [qr.solve_transposed(*factors, ca.jacobian(s, q).T) for s, _, _ in laws]
    d = [mode for _, _, mode in laws]
    n0 = [friction_load.load_vector(functions, e, x, lam0) for e in loaded]
    n1 = [[friction_load.load_vector(functions, e, x, u) for u in units] for e in loaded]
    g, checked = friction_load.coupled([e.params["mu"] for e in loaded], d, n0, n1)
    lam = lam0 - sum(d[j] * g[j] * units[j] for j in range(len(loaded)))
    forces = ca.vertcat(*(f - d[j] * g[j] for j, (_, f, _) in enumerate(laws)))
    outputs = [x.ground_fixed(v) for v in (lam, forces, checked)]
    return ca.Function("prescribed_friction_load", [t, q, q_dot, lam0], outputs,
                       ["t", "q", "q_dot", "lam0"], ["lam", "f", "loads"])
