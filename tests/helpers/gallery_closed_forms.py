"""Closed forms and invariants the gallery models are checked against, written in plain numpy
from textbook mechanics (nothing here calls casmech)."""

from __future__ import annotations

import numpy as np


# ------------------------------------------------------------------------- rigid-body helpers
def rotation(p: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) from unit quaternions p (n, 4) = [e0, e1, e2, e3]."""
    e0, e1, e2, e3 = np.moveaxis(np.atleast_2d(p), -1, 0)
    return np.stack([
        np.stack([1 - 2 * (e2**2 + e3**2), 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)], -1),
        np.stack([2 * (e1 * e2 + e0 * e3), 1 - 2 * (e1**2 + e3**2), 2 * (e2 * e3 - e0 * e1)], -1),
        np.stack([2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), 1 - 2 * (e1**2 + e2**2)], -1),
    ], -2)


def body_state(table, body: str) -> dict[str, np.ndarray]:
    """Position r, rotation A, CM velocity v and global angular velocity w of a body, per row."""
    columns = {key: np.column_stack([table[f"{body}.{c}"] for c in names])
               for key, names in (("r", ("x", "y", "z")), ("p", ("e0", "e1", "e2", "e3")),
                                  ("v", ("vx", "vy", "vz")), ("w", ("wx", "wy", "wz")))}
    columns["A"] = rotation(columns.pop("p"))
    return columns


def global_inertia(state, inertia: np.ndarray) -> np.ndarray:
    return state["A"] @ inertia @ np.swapaxes(state["A"], 1, 2)


def mechanical_energy(model, table) -> np.ndarray:
    """Kinetic + gravitational potential energy, per row (no springs)."""
    energy = 0.0
    for body in model.bodies:
        s = body_state(table, body.name)
        spin = np.einsum("ni,nij,nj->n", s["w"], global_inertia(s, body.inertia), s["w"])
        energy = energy + 0.5 * body.mass * np.sum(s["v"]**2, 1) + 0.5 * spin
        energy = energy - body.mass * s["r"] @ model.gravity
    return energy


def angular_momentum(model, table, point=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Total angular momentum about a fixed point, global frame, per row (n, 3)."""
    total = 0.0
    for body in model.bodies:
        s = body_state(table, body.name)
        spin = np.einsum("nij,nj->ni", global_inertia(s, body.inertia), s["w"])
        total = total + spin + body.mass * np.cross(s["r"] - np.asarray(point), s["v"])
    return total


def linear_momentum(model, table) -> np.ndarray:
    return sum(body.mass * body_state(table, body.name)["v"] for body in model.bodies)


def rotation_about_y(table, body: str) -> np.ndarray:
    """Angle of a body turned about the global y axis only (planar pendulums): 2 atan2(e2, e0)."""
    return 2 * np.arctan2(table[f"{body}.e2"], table[f"{body}.e0"])


# ---------------------------------------------------------------------------------- pendulums
def chain_pendulum(lengths, masses, inertias, g: float) -> tuple[np.ndarray, np.ndarray]:
    """Mass and stiffness matrices of a chain of rods (absolute angles from the downward
    vertical, CM at mid-length, moment J_i about the CM), linearised about hanging at rest:
    M theta'' + K theta = 0 with M_ij = L_i L_j (m_k / 2 + masses below k), k = max(i, j), for
    i != j, M_ii = L_i^2 (m_i / 4 + masses below i) + J_i, K_ii = g L_i (m_i / 2 + masses below)."""
    lengths, masses = np.asarray(lengths, float), np.asarray(masses, float)
    n = len(lengths)
    below = np.array([masses[k + 1:].sum() for k in range(n)])
    mass = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            k = max(i, j)
            share = masses[k] / 4 if i == j else masses[k] / 2
            mass[i, j] = lengths[i] * lengths[j] * (share + below[k])
    mass += np.diag(inertias)
    stiffness = np.diag(g * lengths * (masses / 2 + below))
    return mass, stiffness


def normal_modes(mass, stiffness) -> tuple[np.ndarray, np.ndarray]:
    """Angular frequencies (ascending) and mode shapes (columns, largest entry 1)."""
    values, vectors = np.linalg.eig(np.linalg.solve(mass, stiffness))
    order = np.argsort(values.real)
    vectors = vectors.real[:, order]
    return np.sqrt(values.real[order]), vectors / vectors[np.abs(vectors).argmax(0),
                                                         range(len(order))]


# ----------------------------------------------------------------------------------- heavy top
def steady_precession_rate(m, g, arm, i1_pivot, i3, omega3, tilt) -> float:
    """Slow root of I1 Omega^2 cos(tilt) - I3 omega3 Omega + m g l = 0 (Lagrange top in steady
    precession at constant tilt; Goldstein sec. 5.7)."""
    roots = np.roots([i1_pivot * np.cos(tilt), -i3 * omega3, m * g * arm])
    return float(np.min(roots.real))


# ---------------------------------------------------------------------------------- mechanisms
def cardan_output_speed(omega_in, bend, theta):
    """Hooke joint: output speed for input speed omega_in, theta measured from the input yoke
    pin perpendicular to the plane of the shafts."""
    return omega_in * np.cos(bend) / (1 - np.sin(bend)**2 * np.sin(theta)**2)


def governor_potential_slope(alpha, g, omega, offset, arm):
    """dU/dalpha / m of a flyball arm (ball of isotropic inertia on a light arm hinged at
    `offset` from the spindle, spindle at omega): U/m = -g l cos(a) - omega^2 (d + l sin a)^2/2."""
    return g * arm * np.sin(alpha) - omega**2 * (offset + arm * np.sin(alpha)) * arm * np.cos(
        alpha)


def governor_angle(g, omega, offset, arm) -> float:
    """Steady arm angle: g tan(alpha) = omega^2 (d + l sin(alpha)), by Newton from the d = 0
    answer (bisection-safe here: the slope is monotone on (0, pi/2) for these data)."""
    alpha = np.arccos(min(g / (omega**2 * arm), 1.0))
    for _ in range(50):
        residual = g * np.tan(alpha) - omega**2 * (offset + arm * np.sin(alpha))
        slope = g / np.cos(alpha)**2 - omega**2 * arm * np.cos(alpha)
        alpha -= residual / slope
    return float(alpha)


def rsur_rocker_angle(theta, a, c, coupler, pivot, phi0):
    """Rocker angle phi(theta) of the spatial four-bar: |D + c (0, cos phi, sin phi) -
    a (cos theta, sin theta, 0)| = coupler, by Newton continued along theta from phi0."""
    pivot = np.asarray(pivot, float)
    phi, out = phi0, []
    for th in np.atleast_1d(theta):
        crank = a * np.array([np.cos(th), np.sin(th), 0.0])
        for _ in range(30):
            d = pivot + c * np.array([0.0, np.cos(phi), np.sin(phi)]) - crank
            slope = 2 * d @ (c * np.array([0.0, -np.sin(phi), np.cos(phi)]))
            phi -= (d @ d - coupler**2) / slope
        out.append(phi)
    return np.array(out)


def arm_forward_kinematics(q1, q2, q3, h0, l1, l2):
    """CM of the upper arm and forearm of the 3R elbow arm (pitch angles positive downward)."""
    def place(reach, drop):
        return np.column_stack([reach * np.cos(q1), reach * np.sin(q1), h0 - drop])
    upper = place(l1 / 2 * np.cos(q2), l1 / 2 * np.sin(q2))
    fore = place(l1 * np.cos(q2) + l2 / 2 * np.cos(q2 + q3),
                 l1 * np.sin(q2) + l2 / 2 * np.sin(q2 + q3))
    return upper, fore
