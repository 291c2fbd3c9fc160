"""`repeat` and `{expr}` names (docs/components.md): an N-link chain built with `repeat` is the
same model as the chain written out by hand, number for number and in its dynamics; mistakes in
repeated items are reported at the written item, with the index values of the copy."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import casmech
from casmech.cli import main
from casmech.errors import ModelError
from casmech.schema import load_model_text
from tests.conftest import MODELS

N = 4
T_END = 0.5

HEADER = """\
casmech: 1
name: chain
parameters: {N: 4, L: 0.5, m: 1.0, w: 0.04, w0: 1.0}
"""
BODY = ("{{name: {name}, mass: m, inertia: [m*w**2/6, m*(L**2+w**2)/12, m*(L**2+w**2)/12], "
        "position: [{x}, 0, 0], velocity: [0, w0*({x}), 0], angular_velocity: [0, 0, w0]{more}}}")
JOINT = "{{name: {name}, type: spherical, body_i: {bi}, body_j: {bj}, at: [{x}, 0, 0]{more}}}"

REPEATED = HEADER + f"""\
bodies:
  - {BODY.format(name='"link{i}"', x='(i-1)*L + L/2', more=', repeat: {index: i, from: 1, to: N}')}
joints:
  - {JOINT.format(name='j1', bi='ground', bj='link1', x='0', more='')}
  - {JOINT.format(name='"j{i}"', bi='"link{i-1}"', bj='"link{i}"', x='(i-1)*L',
                  more=', repeat: {index: i, from: 2, to: N}')}
analysis: {{t_end: {T_END}, rtol: 1.0e-8, atol: 1.0e-10}}
"""


def by_hand(names=lambda k: f"link{k}") -> str:
    """The chain of N links written out, item by item, with the numbers of each copy."""
    bodies = [BODY.format(name=names(k), x=f"({k}-1)*L + L/2", more="")
              for k in range(1, N + 1)]
    joints = [JOINT.format(name="j1", bi="ground", bj=names(1), x="0", more="")]
    joints += [JOINT.format(name=f"j{k}", bi=names(k - 1), bj=names(k), x=f"({k}-1)*L", more="")
               for k in range(2, N + 1)]
    return (HEADER + "bodies:\n" + "".join(f"  - {b}\n" for b in bodies) + "joints:\n"
            + "".join(f"  - {j}\n" for j in joints)
            + f"analysis: {{t_end: {T_END}, rtol: 1.0e-8, atol: 1.0e-10}}\n")


def numbers(item) -> list:
    """Every number of a resolved item (arrays, floats, and vectors by key), in field order."""
    out = []
    for f in dataclasses.fields(item):
        value = getattr(item, f.name)
        if isinstance(value, np.ndarray | float | int) and not isinstance(value, bool):
            out.append(np.asarray(value, float))
        elif isinstance(value, dict) and all(isinstance(v, np.ndarray) for v in value.values()):
            out += [np.asarray(value[k], float) for k in sorted(value)]
    return out


def assert_same_numbers(a, b):
    for section in ("bodies", "joints", "forces"):
        items_a, items_b = getattr(a, section), getattr(b, section)
        assert len(items_a) == len(items_b)
        for x, y in zip(items_a, items_b, strict=True):
            assert x.type == y.type if hasattr(x, "type") else True
            for u, v in zip(numbers(x), numbers(y), strict=True):
                np.testing.assert_array_equal(u, v)  # the same arithmetic: bit for bit
    np.testing.assert_array_equal(a.gravity, b.gravity)


def dynamics(model):
    functions = casmech.compile(model)
    result = casmech.analyze(functions, t_end=T_END, output_step=0.01)
    return casmech.results_table(functions, result)


def test_repeat_builds_the_chain_written_by_hand():
    repeated, hand = casmech.loads(REPEATED), casmech.loads(by_hand())
    assert [b.name for b in repeated.bodies] == [b.name for b in hand.bodies]
    assert [(j.name, j.body_i, j.body_j) for j in repeated.joints] == [
        (j.name, j.body_i, j.body_j) for j in hand.joints]
    assert_same_numbers(repeated, hand)
    names_r, values_r = dynamics(repeated)
    names_h, values_h = dynamics(hand)
    assert names_r == names_h
    assert len(values_r) == round(T_END / 0.01) + 1
    # the same numbers in the same order give the same run: every column bit for bit
    np.testing.assert_array_equal(values_r, values_h)


def test_chain_of_component_instances_equals_the_chain_by_hand():
    """models/chain_repeat.yaml: link instances (bodies `link<i>.bar`) placed along x."""
    composed = casmech.load(MODELS / "chain_repeat.yaml")
    hand = casmech.loads(by_hand())
    assert [b.name for b in composed.bodies] == [f"link{k}.bar" for k in range(1, N + 1)]
    assert_same_numbers(composed, hand)
    names_c, values_c = dynamics(composed)
    names_h, values_h = dynamics(hand)
    renamed = [n.replace(".bar.", ".") for n in names_c]
    assert renamed == names_h
    # placement by a pure translation adds the same doubles in another order: measured
    # identical here; 1e-12 allows a last-bit difference in a position
    np.testing.assert_allclose(values_c, values_h, rtol=0, atol=1e-12)


def test_the_number_of_links_is_a_parameter():
    model = casmech.load(MODELS / "chain_repeat.yaml", {"N": "7"})
    assert len(model.bodies) == 7 and len(model.joints) == 7
    tip = model.bodies[-1]
    # the 7th link's centre is at 6.5 L along x, moving with the rigid spin w0 about z
    np.testing.assert_allclose(tip.position, [6.5 * 0.5, 0, 0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(tip.velocity, [0, 1.0 * 6.5 * 0.5, 0], rtol=0, atol=1e-15)
    assert not casmech.load(MODELS / "chain_repeat.yaml", {"N": "1"}).joints[1:]


def test_nested_ranges_and_negative_indices():
    text = HEADER + """\
bodies:
  - {name: "b{i + 2}_{j + 1}", mass: 1, inertia: [1, 1, 1], position: [i, j, "i*j"],
     repeat: [{index: i, from: -1, to: 1}, {index: j, from: 0, to: i + 1}]}
"""
    model = casmech.loads(text)
    expected = [(i, j) for i in (-1, 0, 1) for j in range(0, i + 2)]
    assert [b.name for b in model.bodies] == [f"b{i + 2}_{j + 1}" for i, j in expected]
    np.testing.assert_array_equal([b.position for b in model.bodies],
                                  [[i, j, i * j] for i, j in expected])


# -------------------------------------------------------------------------------- errors
def check(tmp_path, text: str, name: str = "m.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def errors(capsys, path) -> list[str]:
    """`casmech check`'s findings, each with its expected/got/hint lines."""
    assert main(["check", str(path)]) == 1
    found = []
    for line in capsys.readouterr().err.splitlines():
        if line.startswith("  ") and found:
            found[-1] += "\n" + line
        else:
            found.append(line)
    return found


def col(text: str, line: int, needle: str) -> int:
    return text.splitlines()[line - 1].index(needle) + 1


CASES = {  # name: (text, (line, needle) of the finding, code, words the message must hold)
    "non_integer_bound": (HEADER.replace("N: 4", "N: 2.5") + """\
bodies:
  - {name: "b{i}", mass: 1, inertia: [1, 1, 1], position: [i, 0, 0],
     repeat: {index: i, from: 1, to: N}}
""", (6, "to: N"), "E103", ["repeat bound must be an integer", "N = 2.5"]),
    "duplicate_after_expansion": (HEADER + """\
bodies:
  - {name: link, mass: 1, inertia: [1, 1, 1], position: [i, 0, 0],
     repeat: {index: i, from: 1, to: 3}}
""", (5, "name: link"), "E301", ["duplicate name 'link'", "(for i = 2, 3)"]),
    "error_in_a_copy": (HEADER + """\
bodies:
  - {name: "b{i}", mass: 1 - abs(i - 2), inertia: [1, 1, 1], position: [i, 0, 0],
     repeat: {index: i, from: 1, to: 3}}
""", (5, "mass"), "E400", ["mass must be positive", "(for i = 1, 3)", "got: 0"]),
    "unknown_symbol_in_a_name": (HEADER + """\
bodies:
  - {name: "b{i + q}", mass: 1, inertia: [1, 1, 1], position: [i, 0, 0],
     repeat: {index: i, from: 1, to: 3}}
""", (5, "q}"), "E201", ["unknown symbol 'q'"]),
    "unknown_symbol_after_a_longer_index": (HEADER + """\
bodies:
  - {name: "b{i}", mass: 1, inertia: [1, 1, 1], position: ["i*L + q", 0, 0],
     repeat: {index: i, from: 10, to: 11}}
""", (5, "q\""), "E201", ["unknown symbol 'q'", "(for i = 10, 11)"]),
    "index_is_a_parameter": (HEADER + """\
bodies:
  - {name: "b{L}", mass: 1, inertia: [1, 1, 1], position: [0, 0, 0],
     repeat: {index: L, from: 1, to: 3}}
""", (6, "index"), "E301", ["the index 'L' is also a parameter"]),
    "reference_to_a_missing_copy": (HEADER + """\
bodies:
  - {name: "b{i}", mass: 1, inertia: [1, 1, 1], position: [i, 0, 0],
     repeat: {index: i, from: 1, to: N}}
joints:
  - {name: top, type: spherical, body_i: ground, body_j: "b{N+1}", at: [0, 0, 0]}
""", (8, "body_j"), "E300", ["unknown body 'b5'"]),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_repeat_mistakes_are_located_where_they_are_written(case, tmp_path, capsys):
    text, (line, needle), code, words = CASES[case]
    path = check(tmp_path, text)
    found = errors(capsys, path)
    assert len(found) == 1, found
    column = col(text, line, needle)
    if needle.startswith(("body_j", "name", "mass", "index", "to")):  # the value, after 'key: '
        column += len(needle.split(":")[0]) + 2
    assert found[0].startswith(f"{path}:{line}:{column}: error[{code}]"), found[0]
    for word in words:
        assert word in found[0]


def test_a_wrong_repeat_is_a_model_error_not_a_traceback():
    bad = HEADER + """\
bodies:
  - {name: "b{i}", mass: 1, inertia: [1, 1, 1], position: [0, 0, 0],
     repeat: {index: i, from: 1}}
"""
    with pytest.raises(ModelError) as caught:
        casmech.loads(bad)
    assert [(d.code, d.path) for d in caught.value.diagnostics] == [("E100", "bodies[0].repeat.to")]


# ------------------------------------------------------------------------------ limits
def test_copies_are_counted_before_they_are_made():
    """A range of 1e9 (or 5000 x 5000 nested) is refused at once, not after filling memory."""
    import time

    from casmech.schema import repeat

    for bounds in ("{index: i, from: 1, to: 1e9}",
                   "[{index: i, from: 1, to: 5000}, {index: j, from: 1, to: 5000}]"):
        text = ("casmech: 1\nname: many\nbodies:\n  - name: \"b{i}\"\n    repeat: " + bounds +
                "\n    mass: 1\n    inertia: [1, 1, 1]\n    position: [0, 0, 0]\n")
        start = time.perf_counter()
        with pytest.raises(ModelError) as caught:
            load_model_text(text, "m.yaml")
        assert time.perf_counter() - start < 5.0  # ~1 ms; a billion dicts would take minutes
        [diagnostic] = caught.value.diagnostics
        assert diagnostic.code == "E105" and f"more than {repeat.MAX_COPIES}" in \
            diagnostic.message and diagnostic.source.line == 5


def test_a_whole_model_is_bounded_members_of_instances_included():
    """4 items of 6000 copies each are 24000 items: beyond MAX_ITEMS though each repeat is
    within MAX_COPIES; reported once, where the budget ran out."""
    from casmech.schema import repeat

    body = ("  - name: \"{0}{{i}}\"\n    repeat: {{index: i, from: 1, to: 6000}}\n"
            "    mass: 1\n    inertia: [1, 1, 1]\n    position: [0, 0, 0]\n")
    text = "casmech: 1\nname: many\nbodies:\n" + "".join(body.format(n) for n in "abcd")
    with pytest.raises(ModelError) as caught:
        load_model_text(text, "m.yaml")
    [diagnostic] = caught.value.diagnostics
    assert diagnostic.code == "E105" and diagnostic.path == "bodies[3]"
    assert f"more than {repeat.MAX_ITEMS}" in diagnostic.message


def test_items_written_out_are_bounded_too():
    from casmech.schema import repeat

    body = "  - {{name: b{0}, mass: 1, inertia: [1, 1, 1], position: [0, 0, 0]}}\n"
    text = "casmech: 1\nname: many\nbodies:\n" + "".join(body.format(k) for k in
                                                        range(repeat.MAX_ITEMS + 1))
    with pytest.raises(ModelError) as caught:
        load_model_text(text, "m.yaml")
    [diagnostic] = caught.value.diagnostics
    assert (diagnostic.code, diagnostic.path) == ("E105", f"bodies[{repeat.MAX_ITEMS}]")
    assert diagnostic.source.line == 4 + repeat.MAX_ITEMS
