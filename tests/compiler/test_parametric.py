"""model.parametric: the bundle over the symbolic IR, given the model data of a lowering at
other parameter values, equals a fresh build of the model loaded with those values, on every
model in models/ that has parameters; structure-changing values change the signature."""

import numpy as np
import pytest

import casmech
from casmech.equations.functions import build_functions
from casmech.model import parametric
from casmech.model.lower import lower
from casmech.schema.loader import load_document
from tests.conftest import MODELS

WITH_PARAMETERS = sorted(p.name for p in MODELS.glob("*.yaml")
                         if casmech.load(p).parameters)
STRUCTURAL = {"chain_repeat.yaml"}  # its parameters are repeat bounds (integers)


def _moved(path, model, signature: str, rng) -> dict[str, str]:
    """The parameters the file gives as numbers, each moved by up to 5 % (those written as
    expressions follow; integers, e.g. repeat bounds, kept), one after the other, keeping each
    move that leaves the structure as it is (a moved position can take a joint point off an
    axis, a zero of the body-frame geometry: another structure, another build)."""
    written = load_document(model.text, model.file).data.get("parameters") or {}
    moved: dict[str, str] = {}
    for name, value in written.items():
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
