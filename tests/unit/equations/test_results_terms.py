"""The results row's terms of an interpreted bundle (equations.functions.results_terms): above
WHERE_INLINE["results"] bodies its results-only functions are built mapped and expanded; they
equal the bundle's inline ones (the rows' AD over the whole expanded graph: a second
formulation) at random inputs, and so does the results row (runtime.results.row_function)
made of them."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.equations import evaluation, system
from casmech.equations.functions import build_functions, results_terms
from casmech.model.lower import lower
from casmech.runtime.results import row_function
from tests.conftest import ROOT
from tests.unit.equations.test_mapped import MODELS, _close, _random

CASES = {**MODELS, "bouncing_ball": lambda: casmech.load(ROOT / "models" / "bouncing_ball.yaml"),
         "quadruped_legs": lambda: casmech.load(ROOT / "models" / "quadruped_legs.yaml")}


@pytest.fixture
def mapped_results(monkeypatch):
    """Every model's results terms mapped (the threshold lowered to no body)."""
    monkeypatch.setitem(evaluation.WHERE_INLINE, "results", 0)


@pytest.mark.parametrize("name", list(CASES))
def test_mapped_terms_equal_inline(name, mapped_results):
    ir = lower(CASES[name]())
    bundle = build_functions(ir)
    terms = results_terms(bundle)
    inline = build_functions(ir).functions  # a second bundle, its functions inline
    rng = np.random.default_rng(7)
    for term in system.RESULTS:
        function, reference = terms[term], inline[term]
        assert function.is_a("SXFunction") and term not in bundle.functions._built, term
        assert function.name_in() == reference.name_in(), term
        assert function.name_out() == reference.name_out(), term
        for k in range(reference.n_out()):
            assert function.size_out(k) == reference.size_out(k), term
        for _ in range(3):
            inputs = _random(reference, rng)
            for k, (a, b) in enumerate(zip(function.call(inputs), reference.call(inputs),
                                           strict=True)):
                _close(a, b, f"{term}.{reference.name_out(k)}")
    assert hash(terms["phi"]) == hash(bundle.functions["phi"])  # the bundle's (the analyses')


@pytest.mark.parametrize("name", ["motors", "bouncing_ball", "chain4"])
def test_mapped_results_row_equals_inline(name, monkeypatch):
    """The row function over mapped terms (an MXFunction calling them) equals the inline one
    (one SX graph) at random (t, q, q_dot, q_ddot, lam)."""
    ir = lower(CASES[name]())
    want = row_function(build_functions(ir))
    monkeypatch.setitem(evaluation.WHERE_INLINE, "results", 0)
    got = row_function(build_functions(ir))
    assert want.is_a("SXFunction") and got.is_a("MXFunction")
    rng = np.random.default_rng(13)
    for _ in range(3):
        inputs = _random(want, rng)
        _close(got.call(inputs)[0], want.call(inputs)[0], "results row")


def test_built_or_given_terms_are_kept(mapped_results):
    """A function the bundle has built (a run that read the reactions) or was given is used
    as it is; small models, and bundles of compiled functions, keep their own."""
    ir = lower(CASES["motors"]())
    bundle = build_functions(ir)
    built = bundle.functions["reactions"]
    energy = bundle.functions["energy"]
    inputs = energy.mx_in()
    given = ca.Function("energy", inputs, energy.call(inputs), energy.name_in(),
                        energy.name_out())  # (a compiled one's stand-in: an MXFunction)
    bundle.functions["energy"] = given
    terms = results_terms(bundle)
    assert hash(terms["reactions"]) == hash(built) and hash(terms["energy"]) == hash(given)
    assert "body_rates" not in bundle.functions._built  # mapped: the bundle's not built


def test_small_models_keep_the_inline_terms():
    ir = lower(CASES["motors"]())
    assert ir.n_bodies <= evaluation.WHERE_INLINE["results"]
    bundle = build_functions(ir)
    terms = results_terms(bundle)
    assert all(hash(terms[name]) == hash(bundle.functions[name])
               for name in (*system.RESULTS, "phi"))
    assert row_function(bundle).is_a("SXFunction")
