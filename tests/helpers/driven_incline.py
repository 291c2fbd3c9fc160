"""A block driven along an incline by a translational joint with joint friction and a load
part (docs/forces.md#joint-friction): the model the load-friction tests of prescribed motions
and of dynamics runs share, with its constants for their closed forms."""

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
