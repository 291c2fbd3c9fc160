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
  at up to v_bound cannot cross its overlap window within one step (v_bound at least
  `min_closing_speed` of core.options.DynamicsSolver).

A step cap the caller asks for (DynamicsSolver.max_step) applies too: the smaller one wins.
"""

from __future__ import annotations

import numpy as np

from casmech.core.options import DynamicsSolver
from casmech.elements.force_types import entry_of
from casmech.model.ir import ModelIR

DEFAULT = DynamicsSolver()


def _speed_bound(ir: ModelIR, reach: float, duration: float, min_speed: float) -> float:
    speeds = [np.linalg.norm(b.r_dot0) + np.linalg.norm(b.omega0) * reach for b in ir.bodies]
    return max(min_speed, 2 * max(speeds, default=0.0) + np.linalg.norm(ir.gravity) * duration)


def max_step(ir: ModelIR, output_step: float, duration: float,
             settings: DynamicsSolver = DEFAULT) -> float | None:
    """The largest step for this model, or None (no contact, no stop, none asked for:
    SUNDIALS' own)."""
    contacts = [f for f in ir.forces if getattr(entry_of(f.type), "contact", False)]
    asked = settings.max_step
    if not contacts and not ir.limits:
        return None if asked is None else float(asked)
    step = output_step
    windows = [entry_of(f.type).thickness(f.params) for f in contacts
               if entry_of(f.type).thickness is not None]  # sphere pairs: R_i + R_j
    if windows:
        step = min(step, min(windows) / _speed_bound(ir, max(windows), duration,
                                                     settings.min_closing_speed))
    return float(step if asked is None else min(step, asked))


def options(ir: ModelIR, output_step: float, duration: float,
            settings: DynamicsSolver = DEFAULT) -> dict:
    """CVODES's and IDAS's options from the settings: max_num_steps, and max_step_size and
    step0 where there are such."""
    out = {"max_num_steps": settings.max_steps}
    step = max_step(ir, output_step, duration, settings)
    if step is not None:
        out["max_step_size"] = step
    if settings.initial_step is not None:
        out["step0"] = float(settings.initial_step)
    return out
