"""Driven models with joint friction and a load part (docs/forces.md#joint-friction) that the
load-friction tests of prescribed motions and of dynamics runs share, with the constants of
their closed forms: a block driven along an incline, a rotor driven about a horizontal axle."""

import math

import numpy as np

G = 9.81
THETA, M, MU, TC, C = 0.6, 2.0, 0.4, 0.7, 0.3
W = np.array([math.cos(THETA), 0.0, -math.sin(THETA)])  # the slide's axis, down the slope


def driven_incline(displacement: str, after: str) -> str:
    """The model's text: the slide driven by `displacement` (an expression of t), `after`
    the joints (forces, events and the analysis, as YAML lines)."""
    return f"""casmech: 1
name: driven_incline
gravity: [0, 0, -{G}]
bodies:
  - {{name: block, mass: {M}, inertia: [0.1, 0.1, 0.1], position: [0, 0, 0]}}
joints:
  - name: slide
    type: translational
    body_i: ground
    body_j: block
    at: [0, 0, 0]
    axis: [{W[0]}, 0, {W[2]}]
    driver: {{displacement: "{displacement}"}}
    friction: {{coulomb: {TC}, viscous: {C}, mu: {MU}}}
{after}"""


def driven_rotor(analysis: str) -> str:
    """A 3 kg rotor spun about a horizontal axle (y) at SPEED rad/s (replace SPEED), its
    bearing's friction 0.05 N m plus mu 0.3 at radius 0.02 m of the radial load; `analysis`
    the model's analysis mapping (YAML flow text)."""
    return f"""casmech: 1
name: rotor
gravity: [0, 0, -{G}]
bodies:
  - {{name: rotor, mass: 3.0, inertia: [0.1, 0.2, 0.1], position: [0, 0, 0]}}
joints:
  - name: axle
    type: revolute
    body_i: ground
    body_j: rotor
    at: [0, 0, 0]
    axis: [0, 1, 0]
    driver: {{angle: "SPEED * t"}}
    friction: {{coulomb: 0.05, mu: 0.3, radius: 0.02}}
analysis: {analysis}
"""
