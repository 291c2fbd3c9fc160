"""The `events:` block: resolution into the analysis settings and located errors."""

import pytest

from casmech.errors import ModelError
from casmech.schema import load_model_text

HEAD = """casmech: 1
name: m
parameters: {h: 0.9}
bodies:
  - {name: bar, mass: 1, inertia: [1, 1, 1], position: [1, 0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 1, 0]}
  - {name: ball, type: spherical, body_i: ground, body_j: bar, at: [0, 0, 0]}
events:
"""


def load(events: str):
    return load_model_text(HEAD + events, "m.yaml")


def findings(events: str):
    with pytest.raises(ModelError) as caught:
        load(events)
    return caught.value.diagnostics


def test_events_resolve_into_the_analysis_settings():
    model = load('  - {name: hits_bottom, when: "bar.z + h", direction: falling, action: stop}\n'
                 '  - {name: turn, when: "pivot.angle_dot - t * bar.alphay"}\n')
    first, second = model.analysis.events
    assert (first.name, first.direction, first.action) == ("hits_bottom", "falling", "stop")
    assert (second.direction, second.action) == ("both", "log")  # the defaults
    assert first.when.variables == ("bar.z",)  # h is a parameter, bound as a constant
    assert first.when.value(**{"bar.z": -0.5}) == pytest.approx(0.4, rel=0, abs=1e-15)
    assert set(second.when.variables) == {"t", "pivot.angle_dot", "bar.alphay"}
    assert first.source.line == 10


def test_a_model_without_events_has_none():
    assert load_model_text(HEAD.replace("events:\n", ""), "m.yaml").analysis.events == ()


@pytest.mark.parametrize(("when", "message", "col", "hint"), [
    ("bar.zz + h", "body 'bar' has no 'zz'", 22, "did you mean 'z'?"),
    ("2 * pivot.angel", "revolute joint 'pivot' has no 'angel'", 26, "did you mean 'angle'?"),
    ("bra.x", "unknown state 'bra.x': no body or joint 'bra'", 22, "did you mean 'bar.x'?"),
    ("ground.x", "'ground' does not move: it has no state", 22, "name a moving body or a joint"),
    ("pivot.fx", "reaction column 'pivot.fx' cannot be read by an event", 22,
     "events read body columns and joint coordinates (angle, angle_dot)"),
    ("ball.angle", "spherical joint 'ball' has no 'angle'", 22,
     "spherical joints have e0, e1, e2, e3, wx, wy, wz"),
    ("bar.x + hh", "unknown symbol 'hh'", 30, "did you mean 'h'?"),
])
def test_unknown_names_are_located_with_a_hint(when, message, col, hint):
    [diagnostic] = findings(f'  - {{name: e, when: "{when}"}}\n')
    assert (diagnostic.code, diagnostic.path, diagnostic.message) == (
        "E201", "events[0].when", message)
    assert (diagnostic.source.line, diagnostic.source.col, diagnostic.hint) == (10, col, hint)


def test_a_bad_expression_is_located():
    [diagnostic] = findings('  - {name: e, when: "bar.x +* 2"}\n')
    assert (diagnostic.code, diagnostic.source.line, diagnostic.source.col) == ("E200", 10, 29)


def test_a_duplicate_event_name():
    found = findings('  - {name: e, when: "bar.x"}\n  - {name: e, when: "bar.z"}\n')
    assert [(d.code, d.path, d.source.line) for d in found] == [("E301", "events[1].name", 11)]
    assert found[0].message == "duplicate event name 'e' (first used by events[0], line 10)"


def test_direction_and_action_are_checked():
    found = findings('  - {name: e, when: "bar.x", direction: up, action: halt}\n')
    assert [(d.code, d.path) for d in found] == [("E103", "events[0].direction"),
                                                 ("E103", "events[0].action")]
    assert found[0].expected == "rising | falling | both"


def test_not_finite_at_the_initial_state():
    [diagnostic] = findings('  - {name: e, when: "1 / bar.vx"}\n')
    assert (diagnostic.code, diagnostic.message) == (
        "E204", "'1 / bar.vx' evaluates to inf at t = 0, bar.vx = 0")


def test_every_finding_of_several_events_at_once():
    found = findings('  - {name: a, when: "bar.q"}\n  - {name: 1b, when: "pivot.x"}\n')
    assert [(d.code, d.path) for d in found] == [
        ("E201", "events[0].when"), ("E303", "events[1].name"), ("E201", "events[1].when")]


def test_the_body_columns_are_the_results_contracts():
    """schema.events keeps its own copy (schema does not import the runtime)."""
    from casmech.core.columns import BODY_COLUMNS
    from casmech.schema.events import BODY_COLUMNS as READABLE

    assert READABLE == BODY_COLUMNS


CONTACT = """casmech: 1
name: ball
bodies:
  - {name: ball, mass: 1, inertia: [0.004, 0.004, 0.004], position: [0, 0, 1],
     geometry: [{sphere: 0.1}]}
forces:
  - {name: floor, type: sphere_plane, body_i: ground, body_j: ball,
     plane: {at: [0, 0, 0], normal: [0, 0, 1]}, normal: {law: linear, stiffness: 1.0e5}}
events:
"""


def test_contact_columns_are_readable_and_misspelt_ones_located():
    model = load_model_text(CONTACT + '  - {name: touch, when: "floor.gap", '
                                      'direction: falling}\n', "ball.yaml")
    assert model.analysis.events[0].when.variables == ("floor.gap",)
    with pytest.raises(ModelError) as caught:
        load_model_text(CONTACT + '  - {name: touch, when: "floor.gapp"}\n', "ball.yaml")
    [diagnostic] = caught.value.diagnostics
    assert (diagnostic.code, diagnostic.message, diagnostic.hint) == (
        "E201", "'floor' has no column 'gapp'", "did you mean 'gap'?")
