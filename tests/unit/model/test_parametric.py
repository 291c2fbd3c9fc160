"""model.parametric: the bundle over the symbolic IR, given the model data of a lowering at
other parameter values, equals a fresh build of the model loaded with those values, on every
model in models/ that has parameters; structure-changing values change the signature."""

import numpy as np
import pytest

import casmech
from casmech.core.expressions import Number, parse
from casmech.equations.functions import build_functions
from casmech.model import parametric
from casmech.model.lower import lower
from casmech.schema.loader import load_document
from tests.conftest import MODELS

WITH_PARAMETERS = sorted(p.name for p in MODELS.glob("*.yaml")
                         if casmech.load(p).parameters)
STRUCTURAL = {"chain_repeat.yaml"}  # its parameters are repeat bounds (integers)


def _moved(path, model, signature: str, rng) -> dict[str, str]:
    """The parameters the file gives as numbers (with a unit or not), each moved by up to 5 %
    (those written as expressions follow; integers, e.g. repeat bounds, kept), one after the
    other, keeping each move that leaves the structure as it is (a moved position can take a
    joint point off an axis, a zero of the body-frame geometry: another structure, another
    build)."""
    written = load_document(model.text, model.file).data.get("parameters") or {}
    moved: dict[str, str] = {}
    for name, value in written.items():
        if isinstance(value, str) and isinstance(parse(value).root, Number):  # `500 mm`
            value = float(parse(value).evaluate({}))  # moved in SI
        if isinstance(value, float) or (isinstance(value, int) and abs(value) <= 1):
            trial = moved | {name: repr(value * (1 + 0.05 * rng.uniform(-1, 1)))}
            if parametric.data(lower(casmech.load(path, trial)))[1] == signature:
                moved = trial
    return moved


@pytest.mark.parametrize("name", [n for n in WITH_PARAMETERS])
def test_parametric_bundle_equals_a_fresh_build(name):
    rng = np.random.default_rng(sum(map(ord, name)))
    model = casmech.load(MODELS / name)
    split = parametric.split(lower(model))
    symbolic = build_functions(split.ir, split.symbols)
    moved = lower(casmech.load(MODELS / name, _moved(MODELS / name, model, split.signature,
                                                     rng)))
    values, signature = parametric.data(moved)
    assert signature == split.signature  # same structure: the build serves these values
    assert np.any(values != split.values)  # the parameters moved
    fresh = build_functions(moved)
    assert set(symbolic.functions) == set(fresh.functions)
    for function_name, function in fresh.functions.items():
        args = [rng.standard_normal(function.sparsity_in(k).shape)
                for k in range(function.n_in())]
        for got, want in zip(symbolic.evaluate(function_name, *args, values),
                             fresh.evaluate(function_name, *args), strict=True):
            # one expression graph with the numbers as inputs or as constants: round-off,
            # relative to the largest entry (a sum of large terms may cancel to near 0)
            scale = 1 + np.abs(want).max(initial=0)
            np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * scale)


def test_values_are_the_numbers_of_the_numeric_lowering():
    model = casmech.load(MODELS / "me751_pendulum.yaml")
    ir = lower(model)
    split = parametric.split(ir)
    np.testing.assert_array_equal(split.values, parametric.data(ir)[0])  # same walk
    assert split.symbols.numel() == len(split.values)
    assert ir.bodies[0].mass in split.values  # the mass is an entry, not a constant


def test_a_repeat_count_changes_the_signature():
    path = MODELS / "chain_repeat.yaml"
    model = casmech.load(path)
    counts = [name for name, value in model.parameters.items()
              if float(value).is_integer() and value > 1]
    assert counts
    more = casmech.load(path, {counts[0]: repr(int(model.parameters[counts[0]]) + 1)})
    assert len(more.bodies) != len(model.bodies)
    assert parametric.data(lower(more))[1] != parametric.data(lower(model))[1]


ONE_SIDED = """
casmech: 1
name: stop
parameters: {k: 100.0, top: 0.3}
gravity: [0, 0, -9.81]
bodies:
  - {name: bar, mass: 1, inertia: [0.1, 0.1, 0.1], position: [0, 0.5, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [1, 0, 0],
     limit: {upper: top, stiffness: k, damping: 1}}
"""


@pytest.mark.parametrize("side", ["upper", "lower"])
def test_a_one_sided_stop_stays_one_sided(side):
    """A stop's absent bound is an infinity: the split keeps it a number of the structure (it
    is no entry of d: an infinity is not data, and 0 in its place was a stop at 0), so the
    bundle over d equals the numeric build on both sides of 0 and past the bound."""
    model = casmech.loads(ONE_SIDED.replace("upper: top", f"{side}: top"))
    ir = lower(model)
    split = parametric.split(ir)
    assert not np.isinf(split.values).any()
    symbolic, fresh = build_functions(split.ir, split.symbols), build_functions(ir)
    for angle in (-0.6, -0.25, 0.1, 0.5):
        q = np.r_[0.0, 0.5 * np.cos(angle), 0.5 * np.sin(angle), np.cos(angle / 2),
                  np.sin(angle / 2), 0.0, 0.0]
        q_dot = np.r_[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        for name in ("element_outputs", "generalized_forces"):
            got = symbolic.evaluate(name, 0.0, q, q_dot, split.values)
            want = fresh.evaluate(name, 0.0, q, q_dot)
            # the same expressions, numbers as inputs or constants: round-off
            np.testing.assert_allclose(got[0], want[0], rtol=1e-13, atol=1e-13)
