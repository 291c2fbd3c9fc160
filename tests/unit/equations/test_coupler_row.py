"""A constraint row over three bodies (a toy primitive registered here: the distance from the
midpoint of a point on body i and a point on body j to a point on body k, driven in time),
through the builder's row gather (equations.row_kernels, rows): phi, phi_q, nu, gamma, the
variations and the r-omega gamma of both evaluations (inline, mapped; numeric and over the model
data d), and the DAE residuals' element sums, against the same constraint written out by hand
here (its derivatives by CasADi's AD of that hand-written phi)."""

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.elements import primitives
from casmech.equations import rows
from casmech.equations.functions import build_functions, mapped_functions
from casmech.model import parametric
from casmech.model.ir import GROUND_INDEX, PrimitiveIR, RowInfo
from casmech.model.lower import lower
from tests.helpers.equations import (
    assert_mapped_residual_is_inline,
    dense,
    random_unit_p,
    scalar,
)

KIND = "midpoint_distance"
TEXT = """
casmech: 1
name: coupler
bodies:
  - {name: a, mass: 1.0, inertia: [0.1, 0.2, 0.3], position: [1, 0, 0]}
  - {name: b, mass: 2.0, inertia: [0.3, 0.2, 0.4], position: [0, 1, 0]}
  - {name: c, mass: 1.5, inertia: [0.2, 0.2, 0.1], position: [0, 0, 1]}
joints:
  - {name: pin, type: spherical, body_i: ground, body_j: a, at: [0.5, 0, 0]}
"""
S_I, S_J, S_K = np.array([0.3, -0.1, 0.2]), np.array([-0.2, 0.4, 0.1]), np.array([0.1, 0.0, -0.5])
F_TEXT = "0.5 + 0.1*sin(2*t)"


def midpoint_distance(fi, fj, fk, v, f):
    """|(P_i + P_j) / 2 - P_k|^2 - f(t), P the points of the frames (the registered phi)."""
    d = 0.5 * (fi.r + fi.A @ v["s_i"] + fj.r + fj.A @ v["s_j"]) - (fk.r + fk.A @ v["s_k"])
    return d.T @ d - f


@pytest.fixture(autouse=True)
def registered():
    primitives.register(KIND, midpoint_distance, ("s_i", "s_j", "s_k"))
    yield
    primitives.unregister(KIND)


def _row(bodies, label: str) -> PrimitiveIR:
    return PrimitiveIR(KIND, bodies[0], bodies[1], {"s_i": S_I, "s_j": S_J, "s_k": S_K},
                       scalar(F_TEXT), others=tuple(bodies[2:]),
                       row=RowInfo("coupler", KIND, label))


# the rows appended after the joint's: bodies (i, j, k); ground one of them in the second
ROWS = ((0, 1, 2), (2, GROUND_INDEX, 1))


def coupled_ir():
    ir = lower(casmech.loads(TEXT))
    return replace(ir, primitives=ir.primitives + tuple(_row(b, str(b)) for b in ROWS))


# --- the same constraints written out by hand -------------------------------------------------

def _rotation(p):
    """A(p) = (e0^2 - e^T e) I + 2 e e^T + 2 e0 e~ (written here, not casmech.core.euler): the
    homogeneous form, whose Jacobian is the lecture's B(p, a_bar)."""
    e0, e = p[0], p[1:]
    skew = ca.vertcat(ca.horzcat(0, -e[2], e[1]), ca.horzcat(e[2], 0, -e[0]),
                      ca.horzcat(-e[1], e[0], 0))
    return (e0 ** 2 - e.T @ e) * ca.SX.eye(3) + 2 * (e @ e.T) + 2 * e0 * skew


def _g(p):
    """G(p) = [-e, -e~ + e0 I]."""
    e0, e = p[0], p[1:]
    skew = ca.vertcat(ca.horzcat(0, -e[2], e[1]), ca.horzcat(e[2], 0, -e[0]),
                      ca.horzcat(-e[1], e[0], 0))
    return ca.horzcat(-e, -skew + e0 * ca.SX.eye(3))


def _point(q, nb, k, s):
    if k == GROUND_INDEX:
        return ca.DM(s)
    return q[3 * k:3 * k + 3] + _rotation(q[3 * nb + 4 * k:3 * nb + 4 * k + 4]) @ s


def hand_written(nb: int, joint_rows: int):
    """(t, q, q_dot, v, the two rows' phi, phi_q, nu, gamma, [Phi_r, Pi_bar], gamma_hat)."""
    t, q, q_dot = ca.SX.sym("t"), ca.SX.sym("q", 7 * nb), ca.SX.sym("q_dot", 7 * nb)
    v = ca.SX.sym("v", 6 * nb)
    f = 0.5 + 0.1 * ca.sin(2 * t)
    phi = ca.vertcat(*[ca.sumsqr(0.5 * (_point(q, nb, i, S_I) + _point(q, nb, j, S_J))
                                 - _point(q, nb, k, S_K)) - f for i, j, k in ROWS])
    phi_q = ca.jacobian(phi, q)
    nu = -ca.jacobian(phi, t)
    phi_dot = phi_q @ q_dot - nu
    gamma = -(ca.jacobian(phi_dot, q) @ q_dot + ca.jacobian(phi_dot, t))
    pi_bar = [0.5 * phi_q[:, 3 * nb + 4 * k:3 * nb + 4 * k + 4]
              @ _g(q[3 * nb + 4 * k:3 * nb + 4 * k + 4]).T for k in range(nb)]
    jacobian = ca.horzcat(phi_q[:, :3 * nb], *pi_bar)
    p_dot = [0.5 * _g(q[3 * nb + 4 * k:3 * nb + 4 * k + 4]).T @ v[3 * nb + 3 * k:3 * nb + 3 * k + 3]
             for k in range(nb)]
    romega_q_dot = ca.vertcat(v[:3 * nb], *p_dot)
    c = jacobian @ v - nu
    gamma_hat = -(ca.jacobian(c, q) @ romega_q_dot + ca.jacobian(c, t))
    return (t, q, q_dot, v), {"phi": phi, "phi_q": phi_q, "nu": nu, "gamma": gamma,
                              "jacobian": jacobian, "romega_gamma": gamma_hat}


def _close(got, want, what: str) -> None:
    # the same constraint, built by the kernels and by hand: round-off of O(1) numbers
    np.testing.assert_allclose(dense(got), dense(want), rtol=1e-12, atol=1e-12, err_msg=what)


def _state(nb: int, rng):
    q = np.concatenate([rng.normal(size=3 * nb)] + [random_unit_p(rng) for _ in range(nb)])
    return rng.uniform(0, 2), q, rng.normal(size=7 * nb), rng.normal(size=6 * nb)


def _bundles(ir):
    """(label, functions, trailing arguments) of both evaluations, numeric and over d."""
    split = parametric.split(ir)
    inline = build_functions(ir).functions
    over = build_functions(split.ir, split.symbols).functions
    return [("inline", inline, []), ("mapped", mapped_functions(ir), []),
            ("inline over d", over, [split.values]),
            ("mapped over d", mapped_functions(split.ir, split.symbols), [split.values])]


@pytest.mark.parametrize("baked", [True, False])
def test_three_body_rows_equal_the_hand_written_constraint(baked, monkeypatch):
    if not baked:  # the rows' vectors as kernel data
        monkeypatch.setattr(rows, "BAKE_LIMIT", 0)
    ir = coupled_ir()
    keys = rows.row_keys(ir)[-2:]
    assert [key.bodies for key in keys] == [3, 3] and keys[1].ground == "j"
    assert all((key.values is not None) == baked for key in keys)
    nb, m = ir.n_bodies, len(ir.primitives)
    (t, q, q_dot, v), want = hand_written(nb, m - 2)
    hand = {name: ca.Function(name, [t, q, q_dot, v], [value]) for name, value in want.items()}
    rng = np.random.default_rng(7)
    chosen = slice(m - 2, m)  # the coupler rows among phi's
    for label, functions, extra in _bundles(ir):
        for _ in range(3):
            tv, qv, q_dot_v, vv = _state(nb, rng)
            reference = {name: f(tv, qv, q_dot_v, vv) for name, f in hand.items()}
            _close(functions["phi"](tv, qv, *extra)[chosen], reference["phi"], f"{label} phi")
            _close(functions["phi_q"](tv, qv, *extra)[chosen, :], reference["phi_q"],
                   f"{label} phi_q")
            _close(functions["nu"](tv, qv, *extra)[chosen], reference["nu"], f"{label} nu")
            _close(functions["gamma"](tv, qv, q_dot_v, *extra)[chosen], reference["gamma"],
                   f"{label} gamma")
            phi_r, pi_bar = functions["variations"](tv, qv, *extra)
            _close(ca.horzcat(phi_r, pi_bar)[chosen, :], reference["jacobian"],
                   f"{label} variations")
            _close(functions["romega_jacobian"](tv, qv, *extra)[chosen, :],
                   reference["jacobian"], f"{label} romega_jacobian")
            _close(functions["romega_gamma"](tv, qv, vv, *extra)[chosen],
                   reference["romega_gamma"], f"{label} romega_gamma")


@pytest.mark.parametrize("form", ["rp", "romega"])
@pytest.mark.parametrize("kind", ["projection", "ggl"])
def test_three_body_rows_in_the_dae_residual_as_elements(form, kind):
    """The mapped DAE residual (a kernel for the coupler rows over their three bodies) equals
    the inline one over the whole model's matrices."""
    ir = coupled_ir()
    assert_mapped_residual_is_inline(ir, form, kind)
