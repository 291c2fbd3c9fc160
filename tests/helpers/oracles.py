"""The lecture's closed forms of the variations of DP1, DP2, D, CD: the test oracles.

Source: ME751 lecture of 2016-09-30 (/work/shared/reference/000_fa8d33127dca399e.txt), "Virtual
Variation, Basic GCons" in both flavours. Written in plain numpy from the lecture's own derivation,
NOT copied blindly: two of the lecture's final formulas for DP2 carry typos, corrected below with
the line of algebra that proves the correction.

Notation: a_i = A_i a_bar_i, s_i = A_i s_bar_i^P, d_ij = r_j + A_j s_bar_j^Q - r_i - A_i s_bar_i^P.

Each oracle returns four row vectors, one per block:
- delta-p flavour:      (dPhi/dr_i, dPhi/dp_i, dPhi/dr_j, dPhi/dp_j)
- delta-pi_bar flavour: (Phi_r_i, Pi_bar_i, Phi_r_j, Pi_bar_j)
"""

from __future__ import annotations

import numpy as np

from tests.helpers.equations import b_matrix, rotation, skew


class Pair:
    """Poses of bodies i and j and the derived global quantities of a primitive."""

    def __init__(self, r_i, p_i, r_j, p_j, vectors):
        self.r_i, self.p_i = np.asarray(r_i, float), np.asarray(p_i, float)
        self.r_j, self.p_j = np.asarray(r_j, float), np.asarray(p_j, float)
        self.A_i, self.A_j = rotation(self.p_i), rotation(self.p_j)
        self.v = {k: np.asarray(x, float) for k, x in vectors.items()}
        if "s_i" in self.v:
            self.d = (self.r_j + self.A_j @ self.v["s_j"]) - (self.r_i + self.A_i @ self.v["s_i"])


ZERO3 = np.zeros(3)


# --- delta-p flavour: Phi_q -------------------------------------------------------------------

def dp1_q(x: Pair):
    """dPhi/dp_i = a_j^T B(p_i, a_bar_i), dPhi/dp_j = a_i^T B(p_j, a_bar_j), zero r blocks."""
    a_i, a_j = x.A_i @ x.v["a_i"], x.A_j @ x.v["a_j"]
    return ZERO3, a_j @ b_matrix(x.p_i, x.v["a_i"]), ZERO3, a_i @ b_matrix(x.p_j, x.v["a_j"])


def dp2_q(x: Pair):
    """[-a_i^T, d_ij^T B(p_i, a_bar_i) - a_i^T B(p_i, s_bar_i^P), a_i^T, a_i^T B(p_j, s_bar_j^Q)].

    LECTURE TYPO: the lecture prints the p_i block as d_ij^T B(p_i, s_bar_i^P) - a_i^T B(p_i,
    s_bar_i^P). Proof of the correction, with a_i = A(p_i) a_bar_i:
        d/dp_i (a_i^T d_ij) = d_ij^T (d a_i/dp_i) + a_i^T (d d_ij/dp_i)
                            = d_ij^T B(p_i, a_bar_i) + a_i^T (-B(p_i, s_bar_i^P)),
    since d(A(p) a_bar)/dp = B(p, a_bar) by definition of B and d_ij contains -A_i s_bar_i^P.
    """
    a_i = x.A_i @ x.v["a_i"]
    p_i = x.d @ b_matrix(x.p_i, x.v["a_i"]) - a_i @ b_matrix(x.p_i, x.v["s_i"])
    return -a_i, p_i, a_i, a_i @ b_matrix(x.p_j, x.v["s_j"])


def d_q(x: Pair):
    """[-2 d^T, -2 d^T B(p_i, s_bar_i^P), 2 d^T, 2 d^T B(p_j, s_bar_j^Q)]."""
    d = x.d
    return (-2 * d, -2 * d @ b_matrix(x.p_i, x.v["s_i"]), 2 * d,
            2 * d @ b_matrix(x.p_j, x.v["s_j"]))


def cd_q(x: Pair):
    """[-c^T, -c^T B(p_i, s_bar_i^P), c^T, c^T B(p_j, s_bar_j^Q)]."""
    c = x.v["c"]
    return -c, -c @ b_matrix(x.p_i, x.v["s_i"]), c, c @ b_matrix(x.p_j, x.v["s_j"])


# --- delta-pi_bar flavour: [Phi_r, Pi_bar] -----------------------------------------------------

def dp1_pi(x: Pair):
    """Pi_bar_i = -a_bar_j^T A_j^T A_i a_bar_i~, Pi_bar_j = -a_bar_i^T A_i^T A_j a_bar_j~."""
    a_i, a_j = x.v["a_i"], x.v["a_j"]
    return (ZERO3, -a_j @ x.A_j.T @ x.A_i @ skew(a_i), ZERO3,
            -a_i @ x.A_i.T @ x.A_j @ skew(a_j))


def dp2_pi(x: Pair):
    """Pi_bar_i = a_i^T A_i s_bar_i^P~ - d_ij^T A_i a_bar_i~, Pi_bar_j = -a_i^T A_j s_bar_j^Q~.

    LECTURE TYPO: the lecture's last line groups the body-i terms as
    (a_i^T A_i - d_ij^T A_i) s_bar_i^P~ delta pi_bar_i, i.e. it puts s_bar_i^P~ under the d_ij
    term. Its own first line is delta Phi = a_i^T delta d_ij + d_ij^T delta a_i, and
        delta a_i = delta A_i a_bar_i = A_i delta_pi_bar_i~ a_bar_i = -A_i a_bar_i~ delta pi_bar_i,
    so the d_ij term is -d_ij^T A_i a_bar_i~ delta pi_bar_i (a_bar_i~, not s_bar_i^P~); the
    a_i^T delta d_ij term gives +a_i^T A_i s_bar_i^P~ delta pi_bar_i.
    """
    a_i = x.A_i @ x.v["a_i"]
    pi_i = a_i @ x.A_i @ skew(x.v["s_i"]) - x.d @ x.A_i @ skew(x.v["a_i"])
    return -a_i, pi_i, a_i, -a_i @ x.A_j @ skew(x.v["s_j"])


def d_pi(x: Pair):
    """[-2 d^T, 2 d^T A_i s_bar_i^P~, 2 d^T, -2 d^T A_j s_bar_j^Q~]."""
    d = x.d
    return (-2 * d, 2 * d @ x.A_i @ skew(x.v["s_i"]), 2 * d,
            -2 * d @ x.A_j @ skew(x.v["s_j"]))


def cd_pi(x: Pair):
    """[-c^T, c^T A_i s_bar_i^P~, c^T, -c^T A_j s_bar_j^Q~]."""
    c = x.v["c"]
    return -c, c @ x.A_i @ skew(x.v["s_i"]), c, -c @ x.A_j @ skew(x.v["s_j"])


def _angle(oracle_dp1):
    """The `angle` driver is cos f * DP1(v_bar_i, u_bar_j) - sin f * DP1(u_bar_i, u_bar_j)
    (primitives.angle's own definition), so its variation is that combination of DP1 oracles."""

    def oracle(x: Pair, f: float):
        def dp1_of(a_i):
            return oracle_dp1(Pair(x.r_i, x.p_i, x.r_j, x.p_j, {"a_i": a_i, "a_j": x.v["u_j"]}))

        first, second = dp1_of(x.v["v_i"]), dp1_of(x.v["u_i"])
        return tuple(np.cos(f) * a - np.sin(f) * b for a, b in zip(first, second, strict=True))

    return oracle


angle_q = _angle(dp1_q)
angle_pi = _angle(dp1_pi)

DELTA_P = {"dp1": dp1_q, "dp2": dp2_q, "d": d_q, "cd": cd_q}
DELTA_PI = {"dp1": dp1_pi, "dp2": dp2_pi, "d": d_pi, "cd": cd_pi}
