"""Euler-parameter geometry: A(p), G(p), E(p), B(p, a_bar), skew(v).

The only hand-written geometry in casmech (docs/architecture.md). Every function accepts CasADi
SX/MX/DM or numpy inputs and returns CasADi matrices; derivatives of these are left to CasADi.
"""

from __future__ import annotations

from functools import cache

import casadi as ca
import numpy as np


def skew(v) -> ca.SX:
    """The cross-product matrix: skew(a) @ b == cross(a, b)."""
    v = _vector(v, 3)
    return ca.vertcat(
        ca.horzcat(0, -v[2], v[1]),
        ca.horzcat(v[2], 0, -v[0]),
        ca.horzcat(-v[1], v[0], 0),
    )


def rotation(p) -> ca.SX:
    """A(p) = E G^T = (e0^2 - e^T e) I + 2 e e^T + 2 e0 e~: body frame -> global frame.

    On unit p this equals DESIGN's 2[(e0^2 - 1/2) I + e e^T + e0 e~]; the homogeneous form is
    used because its exact Jacobian is the lecture's B(p, a_bar) (the other form adds
    2 a_bar p^T), so AD of every constraint reproduces the lecture's delta-p closed forms.
    """
    p = _vector(p, 4)
    e0, e = p[0], p[1:4]
    return (e0**2 - e.T @ e) * ca.DM.eye(3) + 2 * (e @ e.T) + 2 * e0 * skew(e)


def g_matrix(p) -> ca.SX:
    """G(p) = [-e, -e~ + e0 I] (3x4); omega_bar = 2 G p_dot."""
    p = _vector(p, 4)
    e0, e = p[0], p[1:4]
    return ca.horzcat(-e, -skew(e) + e0 * ca.DM.eye(3))


def e_matrix(p) -> ca.SX:
    """E(p) = [-e, e~ + e0 I] (3x4); omega (global) = 2 E p_dot; A = E G^T."""
    p = _vector(p, 4)
    e0, e = p[0], p[1:4]
    return ca.horzcat(-e, skew(e) + e0 * ca.DM.eye(3))


def b_matrix(p, a_bar) -> ca.SX:
    """B(p, a_bar) = d(A(p) a_bar)/dp = 2[(e0 I + e~) a_bar, e a_bar^T - (e0 I + e~) a_bar~]."""
    p, a_bar = _vector(p, 4), _vector(a_bar, 3)
    e0, e = p[0], p[1:4]
    m = e0 * ca.DM.eye(3) + skew(e)
    return 2 * ca.horzcat(m @ a_bar, e @ a_bar.T - m @ skew(a_bar))


def numeric(function, *args) -> np.ndarray:
    """Evaluate one of the functions above on numbers: euler.numeric(rotation, p) (through a
    casadi.Function built once per function and argument shapes)."""
    arrays = [np.asarray(a, float) for a in args]
    compiled = _function(function, *(a.shape for a in arrays))
    return np.array(compiled(*arrays).full())


def numeric_columns(function, columns: np.ndarray) -> np.ndarray:
    """One of the functions above of one argument, on every column of `columns` by one mapped
    call: the results side by side (e.g. E(p_k) for n Euler parameters: 3 x 4n)."""
    columns = np.asarray(columns, float)
    mapped = _mapped(function, columns.shape[0], columns.shape[1])
    return np.array(mapped(columns).full())


@cache
def _mapped(function, rows: int, count: int) -> ca.Function:
    return _function(function, (rows,)).map(count)


@cache
def _function(function, *shapes) -> ca.Function:
    symbols = [ca.SX.sym(f"a{k}", *(shape if len(shape) == 2 else (int(np.prod(shape)), 1)))
               for k, shape in enumerate(shapes)]
    return ca.Function(function.__name__, symbols, [function(*symbols)])


def _vector(v, n: int):
    """Column vector of length n, keeping symbolic types symbolic."""
    if not isinstance(v, (ca.SX, ca.MX, ca.DM)):
        v = ca.DM(v)
    if v.shape != (n, 1):
        v = ca.reshape(v, n, 1)
    return v
