"""Adding a force element is one registry entry (casmech.elements.force_types;
docs/architecture.md).

A test-only type, `anchor_spring` (a linear spring of zero free length between a point of body_i
and a point of body_j: F = -k d on body j's point, d the vector between the points, potential
1/2 k d.d), is registered by a fixture and removed after. A model using it loads, is checked,
and runs dynamics; its generalized force is minus the gradient of its potential (finite
differences), and a body hung on it at its centre of mass moves as the closed-form 3D
oscillator, like the same model written with a built-in tsda of free length 0.
"""

from typing import Literal

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.core.spec_base import Name, Scalar, Spec, Vector
from casmech.core.values import constant
from casmech.elements import force_types
from casmech.elements.force_types import ForceType
from casmech.elements.forces.terms import at
from casmech.equations.assemble import Coordinates
from casmech.errors import ModelError, failed
from casmech.model.lower import lower
from casmech.schema import export
from tests.conftest import Table


class AnchorSpring(Spec):
    name: Name
    type: Literal["anchor_spring"]
    body_i: Name
    at_i: Vector
    body_j: Name
    at_j: Vector
    stiffness: Scalar


def resolve(check, path, given):
    bodies_ok = check.two_bodies(path, given.body_i, given.body_j)
    points = {key: check.numbers((*path, key), getattr(given, key)) for key in ("at_i", "at_j")}
    k = check.number((*path, "stiffness"), given.stiffness)
    if k is not None and k < 0:
        check.error("E103", (*path, "stiffness"), "stiffness must not be negative", got=f"{k:g}")
        k = None
    if not bodies_ok or failed([*points.values(), k]):
        return None
    return dict(body_i=given.body_i, body_j=given.body_j, vectors=points,
                params={"stiffness": k})


def lower_anchor(force, model, poses):
    points = {"s_i": poses.local(force.body_i, "P", force.vectors["at_i"]),
              "s_j": poses.local(force.body_j, "P", force.vectors["at_j"])}
    return dict(body_i=poses.index[force.body_i], body_j=poses.index[force.body_j],
                points=points, params=dict(force.params))


def law(force, x, read):
    d = at(x.frame(force.body_j), constant(force.points["s_j"])) \
        - at(x.frame(force.body_i), constant(force.points["s_i"]))
    k = force.params["stiffness"]
    return ca.jacobian(d, x.q).T @ (-k * d), 0.5 * k * (d.T @ d)


ANCHOR_SPRING = ForceType("anchor_spring", AnchorSpring, resolve, lower_anchor, law)

MASS, K = 2.0, 50.0
ANCHOR = np.array([0.1, -0.2, 1.5])  # on ground
R0, V0 = np.array([0.4, 0.1, 1.0]), np.array([0.2, -0.3, 0.5])
GRAVITY = np.array([0.0, 0.0, -9.81])


def vec(v) -> str:
    return "[" + ", ".join(repr(float(x)) for x in v) + "]"


def model(force: str) -> str:
    return f"""
casmech: 1
name: anchored
gravity: {vec(GRAVITY)}
bodies:
  - {{name: bob, mass: {MASS}, inertia: [0.3, 0.2, 0.1], position: {vec(R0)},
     orientation: {{axis_angle: {{axis: [1, 2, 3], angle: 0.4}}}},
     velocity: {vec(V0)}, angular_velocity: [1.0, -0.5, 2.0]}}
forces:
  - {{name: spring, body_i: ground, at_i: {vec(ANCHOR)}, body_j: bob, at_j: {vec(R0)},
     {force}}}
analysis: {{type: dynamics, t_end: 1.0, output_step: 0.05, rtol: 1e-10, atol: 1e-12}}
"""


TOY = f"type: anchor_spring, stiffness: {K}"
BUILT_IN = f"type: tsda, stiffness: {K}, free_length: 0"


@pytest.fixture
def anchor_spring():
    force_types.register(ANCHOR_SPRING)
    yield ANCHOR_SPRING
    force_types.unregister(ANCHOR_SPRING.name)


def run(text: str) -> Table:
    functions = casmech.compile(casmech.loads(text))
    return Table(*casmech.results_table(functions, casmech.analyze(functions)))


def test_its_generalized_force_is_minus_the_gradient_of_its_potential(anchor_spring):
    """At random coordinates (Euler parameters not normalized: the law is defined off the
    constraint manifold too), Q = -dV/dq by central differences."""
    text = model(TOY).replace(
        "bodies:\n", "bodies:\n  - {name: base, mass: 1, inertia: [1, 1, 1], "
        "position: [0.3, 0.2, 0.1]}\n").replace("body_i: ground", "body_i: base")
    ir = lower(casmech.loads(text))
    x = Coordinates.create(ir.n_bodies)
    force = ir.forces[0]
    q_law, potential = ANCHOR_SPRING.law(force, x, read=None)
    f = ca.Function("f", [x.q], [q_law, potential])
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = rng.standard_normal(7 * ir.n_bodies)
        step, numeric = 1e-6, np.zeros_like(q)
        for n in range(q.size):
            e = np.zeros_like(q)
            e[n] = step
            numeric[n] = -(float(f(q + e)[1]) - float(f(q - e)[1])) / (2 * step)
        # central differences of a quartic in q (|V| ~ 1e2 at these q): truncation ~1e-10,
        # round-off ~1e-16 |V| / 1e-6 ~ 1e-8
        np.testing.assert_allclose(np.array(f(q)[0]).ravel(), numeric, rtol=1e-6, atol=1e-6)


def test_a_body_on_it_moves_as_the_closed_form_oscillator(anchor_spring):
    """Attached at the centre of mass: r'' = -k/m (r - a) + g, the 3D harmonic oscillator
    about a + m g / k; the same model with a tsda of free length 0 gives the same motion."""
    toy, built_in = run(model(TOY)), run(model(BUILT_IN))
    w = np.sqrt(K / MASS)
    t = toy["t"]
    centre = ANCHOR + MASS * GRAVITY / K
    exact = centre + np.outer(np.cos(w * t), R0 - centre) + np.outer(np.sin(w * t), V0 / w)
    for n, axis in enumerate("xyz"):
        # the integrator at rtol 1e-10 over 1 s (~1 period): global error ~1e-9 of ~1 m
        np.testing.assert_allclose(toy[f"bob.{axis}"], exact[:, n], rtol=0, atol=1e-7)
        np.testing.assert_allclose(toy[f"bob.{axis}"], built_in[f"bob.{axis}"], rtol=0,
                                   atol=1e-7)
    # its potential is in `energy`: conserved (no damping) to the integrator's tolerance
    np.testing.assert_allclose(toy["energy"], toy["energy"][0], rtol=0, atol=1e-6)
    np.testing.assert_allclose(toy["energy"], built_in["energy"], rtol=0, atol=1e-6)


def test_its_checks_are_located_errors(anchor_spring):
    with pytest.raises(ModelError) as found:
        casmech.loads(model(TOY.replace(f"stiffness: {K}", "stiffness: -1")))
    diagnostic = found.value.diagnostics[0]
    assert (diagnostic.code, diagnostic.path) == ("E103", "forces[0].stiffness")


def test_unregistered_the_type_is_unknown_again(anchor_spring):
    """Registering changes the format (the JSON Schema names the type); unregistering
    restores it exactly."""
    assert '"anchor_spring"' in export.schema_text()
    force_types.unregister(ANCHOR_SPRING.name)
    try:
        with pytest.raises(ModelError) as found:
            casmech.loads(model(TOY))
        assert found.value.diagnostics[0].path.startswith("forces[0]")
        assert export.schema_text() == export.DEFAULT_PATH.read_text(encoding="utf-8")
    finally:
        force_types.register(ANCHOR_SPRING)


class AnchorActuated(AnchorSpring):
    type: Literal["anchor_actuated"]


def test_where_states_are_read_follows_the_entries(anchor_spring):
    """The hint of a misplaced state lists the keys the entries name in `state_keys`."""
    assert force_types.state_reading() == "force/torque value, tsda/rsda actuator"
    force_types.register(ForceType("anchor_actuated", AnchorActuated, resolve, lower_anchor,
                                   law, state_keys=("actuator",)))
    try:
        assert force_types.state_reading() == \
            "force/torque value, tsda/rsda/anchor_actuated actuator"
    finally:
        force_types.unregister("anchor_actuated")
