"""The stiffness probe of method auto (runtime.joint_dynamics.choose_method): the spectral
radius of the tree ODE's Jacobian at the run's start, and the DOP853 step it bounds."""

from __future__ import annotations

import numpy as np

from casmech.formulations.joint_system import JointSystem
from casmech.numerics import lazy_jacobian

# h |lambda| on the negative real axis where DOP853's stability function is about -0.7 (its
# boundary, |R| = 1, is near 6.4; tests/unit/runtime/test_stiffness.py computes both from the
# tableau): a step held below it damps the fastest mode instead of meeting the boundary, where
# the error estimate swings and the controller rejects steps
STABLE_REAL = 6.2


def spectral_radius(system: JointSystem, t0: float, x0: np.ndarray) -> float | None:
    """The largest eigenvalue modulus of the tree ODE's Jacobian at (t0, x0); None where the
    Jacobian is not finite (a law not differentiable at t0, or worse: the first results row
    then says so), so that there is no stiffness to judge by."""
    rate = system.dynamics(t0, x0)
    # one evaluation: by forward sweeps, built in a fraction of the RNEA identity's build time
    # (which a run on functional iteration never needs), unless a library gives one
    probe = system.given_jacobian or lazy_jacobian.jacobian(system.dynamics)
    jacobian = np.array(probe(t0, x0, rate)[1].full())
    if not np.all(np.isfinite(jacobian)):
        return None
    return float(np.max(np.abs(np.linalg.eigvals(jacobian))))


def stable_step(radius: float) -> float:
    """The largest DOP853 step method auto allows a tree whose spectral radius at the start is
    `radius` (docs/decisions/method-auto.md): STABLE_REAL / radius, infinite for radius 0."""
    return STABLE_REAL / radius if radius > 0 else np.inf
