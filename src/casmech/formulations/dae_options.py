"""The integrator options an index-2 DAE needs from its start: IDAS's first step and the
absolute tolerances of its algebraic states (runtime.dynamics, runtime.joint_dynamics and
the protocol's built-in formulations read them from here)."""

from __future__ import annotations

import numpy as np

from casmech.core.options import DynamicsSolver

DEFAULT = DynamicsSolver()  # the defaults (core.options)


def algebraic_tolerances(rtol: float, floor: float, v_dot, lam, n_z: int,
                         mu_tolerance: float = DEFAULT.mu_tolerance) -> np.ndarray:
    """Absolute tolerances of [v_dot, lam, mu] in IDAS's Newton test: for v_dot and for lam
    rtol times the largest of the group at the start, at least `floor`; mu_tolerance for mu.

    Per group, not per component: a component that is 0 along the motion (the out-of-plane
    accelerations and reactions of a planar mechanism) carries roundoff of the size of its
    group's largest, which an absolute tolerance of a smaller size never lets converge.
    Andrews' squeezer (accelerations up to 7e3, reactions 1e2) failed at t = 0 with
    the algebraic tolerance 1e-8 for every component, at every rtol from 1e-6 to 1e-10. mu is
    0 along the motion and acts only through q' = q_dot + Phi_q^T mu, so the positions' own
    convergence test covers it; its own test, with 1e-8, failed on the squeezer whatever its
    other tolerances."""
    n_v, m = len(v_dot), len(lam)
    out = np.full(n_z, mu_tolerance)
    out[:n_v] = max(floor, rtol * np.max(np.abs(v_dot), initial=0.0))
    out[n_v:n_v + m] = max(floor, rtol * np.max(np.abs(lam), initial=0.0))
    return out


def initial_step(r, r_ddot, rtol: float, atol: float, interval: float) -> float:
    """IDAS's first step for the index-2 DAE: where an order-1 step's error h^2/2 r_ddot on the
    translations r is a quarter of the tolerance (weighted RMS, IDAS's weights), at most IDAS's
    own 0.001 of the first output interval. IDAS's default from |x_dot| alone gave 3e-17 s on
    benchmarks/chain8, where the iteration matrix of an index-2 DAE (condition ~ 1/h^2) is
    singular in double precision and every Newton iteration failed."""
    weights = rtol * np.abs(r) + atol
    norm = np.sqrt(np.mean((r_ddot / weights) ** 2)) if len(r) else 0.0
    largest = 1e-3 * interval
    return float(min(largest, 0.5 * np.sqrt(2 / norm))) if norm > 0 else largest
