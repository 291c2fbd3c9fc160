"""The step cap of models with contact (runtime/contact_steps.py): without it SUNDIALS steps
over a sphere pair's whole overlap while the bodies fly straight; with it the impact happens,
and exchanges momentum as the restitution says (equal masses: (1 -+ e)/2 v)."""

from __future__ import annotations

import numpy as np
import pytest

import casmech
from casmech.core.options import DynamicsSolver
from casmech.model.lower import lower
from casmech.runtime import contact_steps

SHOT = """
casmech: 1
name: shot
gravity: [0, 0, 0]
bodies:
  - {{name: a, mass: 1, inertia: [1e-5, 1e-5, 1e-5], position: [0, 0, 0], velocity: [1, 0, 0],
     geometry: [{{sphere: 0.01}}]}}
  - {{name: b, mass: 1, inertia: [1e-5, 1e-5, 1e-5], position: [1, 0, 0],
     geometry: [{{sphere: 0.01}}]}}
forces:
  - {{name: hit, type: sphere_sphere, body_i: a, body_j: b,
     normal: {{stiffness: 1e7, restitution: 0.9, impact_velocity: 1}}}}
analysis: {{type: dynamics, t_end: 2.0, output_step: {step}}}
"""


@pytest.mark.parametrize(("formulation", "method"),
                         [("joint", "adams"), ("joint", "bdf"), ("rp", "auto"),
                          ("romega", "auto")])
@pytest.mark.parametrize("step", [0.01, 0.5])
def test_spheres_in_straight_flight_collide_at_any_output_step(formulation, method, step):
    functions = casmech.compile(casmech.loads(SHOT.format(step=step)))
    end = casmech.analyze(functions, formulation=formulation, method=method).to_dataframe()
    end = end.iloc[-1]
    # head-on, equal masses, restitution 0.9 at the closing speed 1 m/s: a keeps 0.05 m/s,
    # b leaves at 0.95 (exact by the law's impact relation; default tolerances rtol 1e-8 and
    # the impact's stiffness leave ~1e-6)
    np.testing.assert_allclose([end["a.vx"], end["b.vx"]], [0.05, 0.95], rtol=0, atol=1e-5)


def test_max_step():
    shot = lower(casmech.loads(SHOT.format(step=0.5)))
    # the pair's thickness 0.02 m over (2 x 1 m/s + 0 g): 0.01 s; and never above the output step
    assert contact_steps.max_step(shot, 0.5, 2.0) == pytest.approx(0.01, rel=1e-15)
    assert contact_steps.max_step(shot, 0.001, 2.0) == 0.001
    plain = lower(casmech.loads(SHOT.format(step=0.5).split("forces:")[0]
                                + "analysis: {type: dynamics}\n"))
    assert contact_steps.max_step(plain, 0.5, 2.0) is None
    assert contact_steps.options(plain, 0.5, 2.0) == {"max_num_steps": 50000}


def test_max_step_asked_for_and_the_least_closing_speed():
    """solver.max_step caps the step with or without contact (the smaller cap wins);
    solver.min_closing_speed bounds the speed a sphere pair's cap assumes from below."""
    shot = lower(casmech.loads(SHOT.format(step=0.5)))
    plain = lower(casmech.loads(SHOT.format(step=0.5).split("forces:")[0]
                                + "analysis: {type: dynamics}\n"))
    assert contact_steps.max_step(plain, 0.5, 2.0, DynamicsSolver(max_step=1e-3)) == 1e-3
    assert contact_steps.max_step(shot, 0.5, 2.0, DynamicsSolver(max_step=1e-3)) == 1e-3
    assert contact_steps.max_step(shot, 0.5, 2.0, DynamicsSolver(max_step=0.1)) == \
        pytest.approx(0.01, rel=1e-15)
    # the pair's 0.02 m over max(10 m/s, 2 x 1 m/s): 2 ms
    slow = DynamicsSolver(min_closing_speed=10.0)
    assert contact_steps.max_step(shot, 0.5, 2.0, slow) == pytest.approx(0.002, rel=1e-15)
    asked = contact_steps.options(plain, 0.5, 2.0, DynamicsSolver(max_steps=7, initial_step=1e-6))
    assert asked == {"max_num_steps": 7, "step0": 1e-6}
