"""The integrator's largest step for a model with contact elements or joint stops.

SUNDIALS interpolates the output grid from its own steps, which grow without bound while the
motion is force-free and smooth (a body in straight flight is integrated exactly by any order),
so a contact that starts between two far-apart steps is never sampled: two small spheres
closing head-on can pass through each other with every formulation and method
(docs/decisions/contact-integration.md). A plane or a stop is a half-space (the
force grows with the depth), so a step past its onset is rejected; a sphere pair is only
`R_i + R_j` thick (the `thickness` of its casmech.elements.force_types entry). `options` caps the
step:

- at the output step, for any contact or stop: the force law is evaluated in every output
  interval;
- for sphere pairs, at (R_i + R_j) / v_bound as well, with v_bound = the largest initial speed
  of a body (its CM speed plus |omega| times the largest radius) + |g| duration: a pair closing
  at up to v_bound cannot cross its overlap window within one step.
"""

from __future__ import annotations

import numpy as np

from casmech.elements.force_types import entry_of
from casmech.model.ir import ModelIR

MIN_SPEED = 1.0  # [m/s] the least closing speed assumed for a sphere pair


def _speed_bound(ir: ModelIR, reach: float, duration: float) -> float:
    speeds = [np.linalg.norm(b.r_dot0) + np.linalg.norm(b.omega0) * reach for b in ir.bodies]
    return max(MIN_SPEED, 2 * max(speeds, default=0.0) + np.linalg.norm(ir.gravity) * duration)


def max_step(ir: ModelIR, output_step: float, duration: float) -> float | None:
    """The largest step for this model, or None (no contact, no stop: SUNDIALS' own)."""
    contacts = [f for f in ir.forces if getattr(entry_of(f.type), "contact", False)]
    if not contacts and not ir.limits:
        return None
    step = output_step
    windows = [entry_of(f.type).thickness(f.params) for f in contacts
               if entry_of(f.type).thickness is not None]  # sphere pairs: R_i + R_j
    if windows:
        step = min(step, min(windows) / _speed_bound(ir, max(windows), duration))
    return float(step)


def options(ir: ModelIR, output_step: float, duration: float) -> dict:
    """{"max_step_size": max_step} for CVODES/IDAS, or {} when there is none."""
    step = max_step(ir, output_step, duration)
    return {} if step is None else {"max_step_size": step}
