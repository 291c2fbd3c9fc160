"""The stiffness probe of method auto (runtime.joint_dynamics.choose_method): the spectral
radius of the tree ODE's Jacobian at the run's start."""

from __future__ import annotations

import numpy as np

from casmech.formulations.joint_system import JointSystem
from casmech.numerics import lazy_jacobian


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
