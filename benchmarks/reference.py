"""An independent reference: the systems' motion is planar (the chain by symmetry, the four-bar
by construction), so it is integrated here in minimal planar coordinates (one absolute angle
per bar, Lagrange multipliers for loop closures) by the classical fixed-step Runge-Kutta method
in NumPy, halving the step until two successive solutions at T_CHECK agree to within AGREE
(the finer one is the reference; RK4's error then is about 1/15 of that difference). None of
casmech, Exudyn or MuJoCo is involved, and it needs nothing beyond NumPy.

Kinematics: the proximal end of bar k is b_k + sum_j P[k, j] L_j u(theta_j), u = (cos, sin) in
the plane (P from the joint tree); a point at fraction f along bar k adds f L_k u(theta_k).
Equations of motion (uniform bars, transverse moment It = m L^2/12 about the plane's normal):
    M(theta) theta'' + Phi_theta^T lam = G(theta) + S(theta) theta'^2,
    Phi_theta theta'' = gamma(theta, theta')                         (loop closures)
with W = (C^T diag(m) C) * (L L^T), C = P + diag(1/2) (the CM rows),
M = W * cos(theta_i - theta_j) + diag(It), S_il = W_il sin(theta_l - theta_i),
G_i = sum_k m_k C[k, i] L_i u'(theta_i) . g.
"""

from __future__ import annotations

import math

import numpy as np
from systems import T_CHECK, System

FIRST_STEP = 1e-3  # s
AGREE = 1e-12  # m, successive halvings must agree to this (max over the measured points)
MAX_HALVINGS = 8


class Planar:
    def __init__(self, system: System):
        self.system = system
        e1, e2 = (np.array(e) for e in system.plane)
        normal = np.cross(e1, e2)
        self.e1, self.e2 = e1, e2
        bars = system.bars
        n = len(bars)
        index = {bar.name: k for k, bar in enumerate(bars)}
        self.L = np.array([bar.length for bar in bars])
        self.m = np.array([bar.mass for bar in bars])
        self.It = self.m * self.L**2 / 12.0
        self.theta0 = np.array([math.atan2(bar.axis @ e2, bar.axis @ e1) for bar in bars])
        for bar in bars:
            if abs(bar.axis @ normal) > 1e-12 or abs(np.array(bar.start) @ normal) > 1e-12:
                raise ValueError(f"{bar.name} is not in the plane of motion")
        g = np.array(system.gravity)
        if abs(g @ normal) > 1e-12:
            raise ValueError("gravity is not in the plane of motion")
        self.g = np.array([g @ e1, g @ e2])

        def planar(p):
            return np.array([np.asarray(p) @ e1, np.asarray(p) @ e2])

        def fraction(bar, point):
            return float((np.asarray(point) - np.array(bar.start)) @ bar.axis / bar.length)

        self.P = np.zeros((n, n))
        self.b = np.zeros((n, 2))
        done = set()
        pending = list(system.tree_joints)
        while pending:  # parents before children
            joint = next(j for j in pending if j.parent == "ground" or j.parent in done)
            pending.remove(joint)
            k = index[joint.child]
            if joint.parent == "ground":
                self.b[k] = planar(joint.at)
            else:
                p = index[joint.parent]
                self.P[k] = self.P[p]
                self.P[k, p] += fraction(bars[p], joint.at)
                self.b[k] = self.b[p]
            done.add(joint.child)
        # loop closures: the joint point through the parent minus through the child (2 rows)
        self.D, self.d = [], []
        for joint in system.loop_joints:
            i, j = index[joint.parent], index[joint.child]
            row = self.P[i] - self.P[j]
            row[i] += fraction(bars[i], joint.at)
            row[j] -= fraction(bars[j], joint.at)
            self.D.append(row)
            self.d.append(self.b[i] - self.b[j])
        C = self.P + 0.5 * np.eye(n)
        self.C = C
        self.W = (C.T @ np.diag(self.m) @ C) * np.outer(self.L, self.L)
        self.Gc = (self.m @ C) * self.L  # G_i = Gc_i u'(theta_i) . g

    def rhs(self, t, y):
        n = len(self.L)
        theta, omega = y[:n], y[n:]
        diff = theta[None, :] - theta[:, None]  # theta_j - theta_i
        mass = self.W * np.cos(diff) + np.diag(self.It)
        du = np.stack([-np.sin(theta), np.cos(theta)])  # u'(theta), 2 x n
        u = np.stack([np.cos(theta), np.sin(theta)])
        force = self.Gc * (self.g @ du) + (self.W * np.sin(diff)) @ omega**2
        if not self.D:
            return np.concatenate([omega, np.linalg.solve(mass, force)])
        rows = []
        gamma = []
        for row in self.D:
            rows.append(du * (row * self.L))  # 2 x n
            gamma.append((u * (row * self.L)) @ omega**2)
        phi_q = np.vstack(rows)
        m = phi_q.shape[0]
        lhs = np.block([[mass, phi_q.T], [phi_q, np.zeros((m, m))]])
        sol = np.linalg.solve(lhs, np.concatenate([force, np.concatenate(gamma)]))
        return np.concatenate([omega, sol[:n]])

    def constraint(self, theta) -> float:
        u = np.stack([np.cos(theta), np.sin(theta)])
        return max((float(np.max(np.abs(d + (u * (row * self.L)).sum(axis=1))))
                    for row, d in zip(self.D, self.d, strict=True)), default=0.0)

    def points(self, theta) -> np.ndarray:
        """CM and tip of every bar (global 3D), as systems.points orders them."""
        u = np.stack([np.cos(theta), np.sin(theta)], axis=1)  # n x 2
        out = []
        for k in range(len(self.L)):
            proximal = self.b[k] + (self.P[k] * self.L) @ u
            for f in (0.5, 1.0):
                p = proximal + f * self.L[k] * u[k]
                out.append(p[0] * self.e1 + p[1] * self.e2)
        return np.array(out)

    def rk4(self, t_end: float, h: float) -> np.ndarray:
        steps = int(round(t_end / h))
        h = t_end / steps
        y = np.concatenate([self.theta0, np.zeros_like(self.theta0)])
        t = 0.0
        for k in range(steps):
            t = k * h
            k1 = self.rhs(t, y)
            k2 = self.rhs(t + h / 2, y + h / 2 * k1)
            k3 = self.rhs(t + h / 2, y + h / 2 * k2)
            k4 = self.rhs(t + h, y + h * k3)
            y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return y[:len(self.L)]

    def solve(self, t_end: float = T_CHECK) -> dict:
        """Points at t_end; `agreement`: distance between the last two step sizes' points."""
        h = FIRST_STEP
        previous = self.points(self.rk4(t_end, h))
        evaluations = 4 * int(round(t_end / h))
        for _ in range(MAX_HALVINGS):
            h /= 2
            theta = self.rk4(t_end, h)
            current = self.points(theta)
            evaluations += 4 * int(round(t_end / h))
            agreement = float(np.max(np.linalg.norm(current - previous, axis=1)))
            if agreement <= AGREE:
                return {"points": current, "step": h, "agreement": agreement,
                        "evaluations": evaluations, "constraint": self.constraint(theta)}
            previous = current
        raise RuntimeError(f"RK4 reference: step halvings still differ by {agreement:.1e} m "
                           f"at h = {h:g} s")
