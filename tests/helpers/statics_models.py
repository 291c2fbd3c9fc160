"""Small models for the statics and modal tests, as YAML text with their closed-form data."""

import casmech

G = 9.81

# A uniform bar on a revolute joint about y at the origin, held by an rsda whose rest pose is
# upright. The file's pose is tilted by theta0 from the upward vertical (the rsda's angle is 0
# there, so free_angle -theta0 puts its rest upright): k theta = m g l sin(theta), l = L/2.
RSDA_PENDULUM = """
casmech: 1
name: rsda_pendulum
parameters: {m: 2.0, L: 1.0, w: 0.05, k: 5.0, theta0: 0.0}
gravity: [0, 0, -9.81]
bodies:
  - name: bar
    mass: m
    inertia: [m * (L**2 + w**2) / 12, m * (L**2 + w**2) / 12, m * w**2 / 6]
    position: [L/2 * sin(theta0), 0, L/2 * cos(theta0)]
    orientation: {axis_angle: {axis: [0, 1, 0], angle: theta0}}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 1, 0]}
forces:
  - {name: spring, type: rsda, joint: pivot, stiffness: k, free_angle: -theta0}
analysis: {type: statics}
"""

# A block on a translational joint along x, a tsda spring-damper along x from a ground point;
# gravity across the slide. Closed forms: omega_n = sqrt(k/m), zeta = c / (2 sqrt(k m)),
# the slide carries the weight, the spring the push p: deflection p / k.
SPRING_MASS = """
casmech: 1
name: spring_mass
parameters: {m: 3.0, k: 120.0, c: 4.0, p: 6.0}
gravity: [0, 0, -9.81]
bodies:
  - {name: block, mass: m, inertia: [0.02, 0.03, 0.04], position: [1, 0, 0]}
joints:
  - {name: slide, type: translational, body_i: ground, body_j: block, at: [1, 0, 0],
     axis: [1, 0, 0]}
forces:
  - {name: spring, type: tsda, body_i: ground, at_i: [0, 0, 0], body_j: block, at_j: [1, 0, 0],
     stiffness: k, damping: c}
  - {name: push, type: force, body: block, at: [1, 0, 0], value: [p, 0, 0]}
analysis: {type: statics}
"""

# A rod hanging from a revolute about y (compound pendulum): omega^2 = m g l / (I + m l^2).
HANGING_ROD = """
casmech: 1
name: hanging_rod
parameters: {m: 1.5, L: 0.8, w: 0.03, theta0: 0.7}
gravity: [0, 0, -9.81]
bodies:
  - name: rod
    mass: m
    inertia: [m * (L**2 + w**2) / 12, m * (L**2 + w**2) / 12, m * w**2 / 6]
    position: [-L/2 * sin(theta0), 0, -L/2 * cos(theta0)]
    orientation: {axis_angle: {axis: [0, 1, 0], angle: theta0}}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: rod, at: [0, 0, 0], axis: [0, 1, 0]}
analysis: {type: modal}
"""

# A four-bar hanging in the x-z plane from ground pivots O2 = (0, 0, 0) and O4 = (d, 0, 0),
# four revolutes about y (3 redundant rows), drawn at a pose that is not its equilibrium; each
# rod's body z axis along the rod.
HANGING_FOUR_BAR = """
casmech: 1
name: hanging_four_bar
parameters:
  m: 1.0
  w: 0.04
  d: 1.2
  Bx: 0.3
  Bz: -0.9
  Cx: 1.5
  Cz: -1.1
  a: sqrt(Bx**2 + Bz**2)
  b: sqrt((Cx - Bx)**2 + (Cz - Bz)**2)
  c: sqrt((Cx - d)**2 + Cz**2)
gravity: [0, 0, -9.81]
bodies:
  - name: crank
    mass: m
    inertia: [m * (a**2 + w**2) / 12, m * (a**2 + w**2) / 12, m * w**2 / 6]
    position: [Bx / 2, 0, Bz / 2]
    orientation: {axis_angle: {axis: [0, 1, 0], angle: "atan2(Bx, Bz)"}}
  - name: coupler
    mass: 2 * m
    inertia: [2 * m * (b**2 + w**2) / 12, 2 * m * (b**2 + w**2) / 12, 2 * m * w**2 / 6]
    position: [(Bx + Cx) / 2, 0, (Bz + Cz) / 2]
    orientation: {axis_angle: {axis: [0, 1, 0], angle: "atan2(Cx - Bx, Cz - Bz)"}}
  - name: rocker
    mass: m
    inertia: [m * (c**2 + w**2) / 12, m * (c**2 + w**2) / 12, m * w**2 / 6]
    position: [(d + Cx) / 2, 0, Cz / 2]
    orientation: {axis_angle: {axis: [0, 1, 0], angle: "atan2(Cx - d, Cz)"}}
joints:
  - {name: o2, type: revolute, body_i: ground, body_j: crank, at: [0, 0, 0], axis: [0, 1, 0]}
  - {name: b, type: revolute, body_i: crank, body_j: coupler, at: [Bx, 0, Bz], axis: [0, 1, 0]}
  - {name: c, type: revolute, body_i: coupler, body_j: rocker, at: [Cx, 0, Cz], axis: [0, 1, 0]}
  - {name: o4, type: revolute, body_i: ground, body_j: rocker, at: [d, 0, 0], axis: [0, 1, 0]}
analysis: {type: modal}
"""

FREE_BODY = """
casmech: 1
name: free_body
gravity: [0, 0, -9.81]
bodies:
  - {name: ball, mass: 1.0, inertia: [0.1, 0.1, 0.1], position: [0, 0, 1]}
analysis: {type: statics}
"""

# gravity along the hinge axis: the arm's angle has zero stiffness
VERTICAL_HINGE = """
casmech: 1
name: vertical_hinge
gravity: [0, 0, -9.81]
bodies:
  - {name: arm, mass: 1.0, inertia: [0.1, 0.1, 0.1], position: [0.5, 0, 0]}
joints:
  - {name: hinge, type: revolute, body_i: ground, body_j: arm, at: [0, 0, 0], axis: [0, 0, 1]}
analysis: {type: statics}
"""


def compiled(text: str, **parameters):
    """The interpreted bundle of a model text with parameter overrides."""
    overrides = {name: repr(float(value)) for name, value in parameters.items()}
    return casmech.compile(casmech.loads(text, overrides=overrides))


def row(functions, result) -> dict:
    names, values = casmech.results_table(functions, result)
    assert values.shape[0] == 1
    return dict(zip(names, values[0], strict=True))
