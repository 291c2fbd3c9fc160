"""Spatial (6-D) vector algebra in SX, angular part first (Featherstone 2008, ch. 2)."""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.core import euler


def cross_motion(v, m):
    """v x m for motion vectors (6x1)."""
    w, lin = v[0:3], v[3:6]
    return ca.vertcat(ca.cross(w, m[0:3]), ca.cross(w, m[3:6]) + ca.cross(lin, m[0:3]))


def cross_force(v, f):
    """v x* f for a motion vector v and a force f."""
    w, lin = v[0:3], v[3:6]
    return ca.vertcat(ca.cross(w, f[0:3]) + ca.cross(lin, f[3:6]), ca.cross(w, f[3:6]))


def transform(e, r):
    """Plucker motion transform to a frame rotated by e (old -> new coordinates) whose origin
    is r in old coordinates."""
    zero = ca.SX.zeros(3, 3)
    return ca.vertcat(ca.horzcat(e, zero), ca.horzcat(-e @ euler.skew(r), e))


def motion(e, r, m):
    """transform(e, r) @ m without the 6x6 matrix: (E w, E (v - r x w))."""
    w = e @ m[0:3]
    return ca.vertcat(w, e @ m[3:6] - ca.cross(e @ r, w))


def force_back(e, r, f):
    """transform(e, r)^T @ f: a force in the new frame back in the old one."""
    n, lin = e.T @ f[0:3], e.T @ f[3:6]
    return ca.vertcat(n + ca.cross(r, lin), lin)


def selection(subspace) -> list[int] | None:
    """The rows a constant motion subspace selects (one 1 per column, zeros elsewhere), else
    None."""
    if not subspace.size2() or not subspace.is_constant():
        return None
    matrix = np.array(ca.DM(subspace).full())
    rows = [int(np.flatnonzero(column)[0]) if np.count_nonzero(column) == 1
            and np.flatnonzero(column).size and column[np.flatnonzero(column)[0]] == 1 else -1
            for column in matrix.T]
    return rows if min(rows) >= 0 and len(set(rows)) == len(rows) else None


def transformed_inertia(e, r, inertia):
    """X^T I X for the motion transform X = transform(e, r) and a symmetric 6x6 I: rotated
    blockwise (E^T . E), then shifted by R = r~ as T^T I T with T = [[1, 0], [-R, 1]] (10 %
    fewer instructions than the two 6x6 products on the chains)."""
    a, b, c = inertia[0:3, 0:3], inertia[0:3, 3:6], inertia[3:6, 3:6]
    a, b, c = e.T @ a @ e, e.T @ b @ e, e.T @ c @ e
    skew = euler.skew(r)
    top = b + skew @ c
    return ca.vertcat(ca.horzcat(a + skew @ b.T - top @ skew, top),
                      ca.horzcat(b.T - c @ skew, c))


def moved(frame, motion):
    """Motion vectors (6 x k) at a frame's origin in its coordinates -> at the body origin in
    body coordinates; `frame` = (its axes as columns, its origin), both in the body frame."""
    axes, origin = (ca.DM(v) for v in frame)
    omega = axes @ motion[0:3, :]
    velocity = axes @ motion[3:6, :] - ca.cross(omega, ca.repmat(origin, 1, motion.size2()))
    return ca.vertcat(omega, velocity)


def inertia(mass: float, rotational: np.ndarray) -> ca.DM:
    """Spatial inertia at the CM in the body frame."""
    zero = np.zeros((3, 3))
    return ca.DM(np.block([[rotational, zero], [zero, mass * np.eye(3)]]))
