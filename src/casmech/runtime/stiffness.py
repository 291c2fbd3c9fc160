"""The stiffness probe of method auto (runtime.joint_dynamics.choose_method): the fastest decay
rate of the tree ODE's linearization at the run's start, the largest -Re(lambda) over the
eigenvalues lambda of its Jacobian. A mode that decays that fast is what BDF steps over and
Adams must resolve; a fast mode that oscillates (a stiff spring lightly damped) both methods
resolve alike, so its frequency is not counted (docs/decisions/method-auto.md)."""

from __future__ import annotations

import numpy as np

from casmech.formulations.joint_system import JointSystem
from casmech.numerics import lazy_jacobian


def decay_rate(system: JointSystem, t0: float, x0: np.ndarray) -> float | None:
    """The largest -Re(lambda) over the eigenvalues of the tree ODE's Jacobian at (t0, x0), at
    least 0; None where the Jacobian is not finite (a law not differentiable at t0, or worse:
    the first results row then says so), so that there is no stiffness to judge by."""
    rate = system.dynamics(t0, x0)
    # one evaluation: by forward sweeps, built in a fraction of the RNEA identity's build time
    # (which a run on functional iteration never needs), unless a library gives one
    probe = system.given_jacobian or lazy_jacobian.jacobian(system.dynamics)
    jacobian = np.array(probe(t0, x0, rate)[1].full())
    if not np.all(np.isfinite(jacobian)):
        return None
    return max(0.0, float(-np.min(np.linalg.eigvals(jacobian).real)))
