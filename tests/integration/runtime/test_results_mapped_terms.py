"""A run's results table over the mapped results terms (equations.functions.results_terms,
the threshold WHERE_INLINE["results"] lowered to every model) equals the one over the inline
terms, and the per-row computation over the bundle's inline functions (runtime.results.row)."""

import numpy as np
import pytest

import casmech
from casmech.equations import evaluation
from casmech.runtime.results import row, row_function, table
from tests.conftest import MODELS


@pytest.mark.parametrize("path, kwargs", [
    ("bouncing_ball.yaml", {"t_end": 0.3}),  # a contact's outputs (element_outputs)
    ("motor_crank.yaml", {"t_end": 0.3}),  # an effort motor's reaction
    ("bricard.yaml", {"t_end": 0.2, "formulation": "romega"}),  # closed loop, a dropped row
])
def test_mapped_table_equals_inline(path, kwargs, monkeypatch):
    model = casmech.load(MODELS / path)
    inline = casmech.compile(model)
    result = casmech.analyze(inline, **kwargs)
    names, want = table(inline, result)
    monkeypatch.setitem(evaluation.WHERE_INLINE, "results", 0)
    mapped = casmech.compile(model)
    assert row_function(mapped).is_a("MXFunction")  # the mapped terms, called
    got_names, got = table(mapped, result)
    per_row = np.array([row(inline, *state) for state in
                        zip(result.times, result.q, result.q_dot, result.q_ddot, result.lam,
                            strict=True)])
    assert got_names == names and got.shape == want.shape == per_row.shape
    scale = np.maximum(1.0, np.max(np.abs(want), axis=0))
    # the same algebra grouped differently (kernels vs one graph): round-off relative to each
    # column's scale
    np.testing.assert_allclose(got / scale, want / scale, rtol=0, atol=1e-12)
    # and the bundle's inline functions row by row (these models' reactions in the frame
    # the row gives them): the same round-off
    np.testing.assert_allclose(got / scale, per_row / scale, rtol=0, atol=1e-12)
