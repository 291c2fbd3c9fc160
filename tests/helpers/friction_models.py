"""Driven models with joint friction and a load part (docs/forces.md#joint-friction) that the
load-friction tests of prescribed motions and of dynamics runs share, with the constants of
their closed forms: a block driven along an incline, a rotor driven about a horizontal axle, a
slider-crank with load parts at its crank bearing and its slide."""

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


A_CRANK, B_ROD, W0, ANGLE0 = 0.5, 2.0, 2.5, 0.3
CRANK_DRIVER = f'driver: {{angle: "{ANGLE0} + {W0} * t"}}'  # the crank at a constant rate


def slider_crank(crank: str, analysis: str, t_end: float, output_step: float) -> str:
    """models/slider_crank.yaml's mechanism under gravity along -y (the slider pressed onto
    its rail by its weight and the rod's force), with friction with load parts at the crank
    bearing and the slide; `crank` the crank bearing's further keys (its driver or motor)."""
    return f"""casmech: 1
name: slider_crank_friction
gravity: [0, -{G}, 0]
bodies:
  - {{name: crank, mass: 1.0, inertia: [0.0003, 0.021, 0.021], position: [{A_CRANK / 2}, 0, 0]}}
  - {{name: rod, mass: 2.0, inertia: [0.0005, 0.67, 0.67], position: [{A_CRANK + B_ROD / 2}, 0, 0]}}
  - {{name: slider, mass: 0.5, inertia: [0.001, 0.001, 0.001], position: [{A_CRANK + B_ROD}, 0, 0]}}
joints:
  - {{name: crank_pivot, type: revolute, body_i: ground, body_j: crank, at: [0, 0, 0],
     axis: [0, 0, 1], friction: {{coulomb: 0.05, mu: 0.2, radius: 0.02}}, {crank}}}
  - {{name: crank_pin, type: spherical, body_i: crank, body_j: rod, at: [{A_CRANK}, 0, 0]}}
  - {{name: wrist_pin, type: universal, body_i: slider, body_j: rod, at: [{A_CRANK + B_ROD}, 0, 0],
     axis_i: [0, 0, 1], axis_j: [0, 1, 0]}}
  - {{name: slide, type: translational, body_i: ground, body_j: slider,
     at: [{A_CRANK + B_ROD}, 0, 0], axis: [1, 0, 0], friction: {{viscous: 0.1, mu: 0.3}}}}
analysis: {{type: {analysis}, t_end: {t_end}, output_step: {output_step}, rtol: 1.0e-11,
           atol: 1.0e-12}}
"""
