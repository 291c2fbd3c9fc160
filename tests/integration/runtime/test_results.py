"""Results and their table (runtime.results): blocks of rows, one mapped call for the table,
and no CasADi call per output row in a dynamics run."""


import numpy as np
import pytest

import casmech
from casmech.runtime.results import Result, row, table
from tests.conftest import MODELS, count_calls


def per_row(functions, result):
    return np.array([row(functions, *state) for state in
                     zip(result.times, result.q, result.q_dot, result.q_ddot, result.lam,
                         strict=True)])


@pytest.mark.parametrize("path, kwargs", [
    ("bricard.yaml", {"t_end": 0.3, "formulation": "romega"}),  # closed loop, a dropped row
    ("four_bar.yaml", {"t_end": 0.3}),  # inverse dynamics: rows appended one at a time
    ("double_pendulum.yaml", {"t_end": 0.3, "mode": "compiled"}),  # compiled bundle: MX map
])
def test_table_equals_the_per_row_computation(path, kwargs, quick_builds):
    """The mapped table against `row` evaluated row by row, to 1e-12 relative to each
    column's scale (the same operations in another evaluation order)."""
    mode = kwargs.pop("mode", "interpreted")
    functions = casmech.compile(casmech.load(MODELS / path), mode=mode)
    result = casmech.analyze(functions, **kwargs)
    names, values = table(functions, result)
    expected = per_row(functions, result)
    assert values.shape == (len(result), len(names)) == expected.shape
    scale = np.maximum(1.0, np.max(np.abs(expected), axis=0))
    np.testing.assert_allclose(values / scale, expected / scale, rtol=0, atol=1e-12)


def test_extend_and_append_build_the_same_result():
    """Blocks and single rows mix; reads give times as floats, states as rows x n arrays;
    the progress callback sees every row's time once, in order."""
    rng = np.random.default_rng(1)
    times = np.linspace(0, 1, 7)
    states = [rng.normal(size=(7, n)) for n in (14, 14, 14, 5)]
    seen = []
    by_rows, by_blocks = Result("dynamics"), Result("dynamics", on_row=seen.append)
    for k, t in enumerate(times):
        by_rows.append(t, *(s[k] for s in states))
    by_blocks.extend(times[:3], *(s[:3] for s in states))
    by_blocks.append(times[3], *(s[3] for s in states))
    by_blocks.extend(times[4:], *(s[4:] for s in states))
    assert seen == by_blocks.times == by_rows.times == times.tolist()
    # the times as one array: the same floats as the list
    np.testing.assert_array_equal(by_blocks.t, np.array(by_rows.times))
    assert len(by_blocks) == len(by_rows) == 7
    for name, value in zip(("q", "q_dot", "q_ddot", "lam"), states, strict=True):
        np.testing.assert_array_equal(getattr(by_blocks, name), value)  # copied exactly
        np.testing.assert_array_equal(getattr(by_rows, name), value)
    with pytest.raises(ValueError, match="q: expected 2 rows"):
        by_blocks.extend(times[:2], *(s[:3] for s in states))


@pytest.mark.parametrize("formulation", ["rp", "romega"])
def test_calls_do_not_grow_with_the_rows(monkeypatch, formulation):
    """A GGL dynamics run and its table: the same CasADi calls from Python for 50 and for
    500 output rows over the same span (IDAS, the output columns and the table are one call
    each, whatever the number of rows)."""
    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    # functions built once per bundle (the table's row function) are built here, not counted
    table(functions, casmech.analyze(functions, "dynamics", t_end=0.1, formulation=formulation))
    counts = {}
    for step in (0.02, 0.002):
        calls = count_calls(monkeypatch)
        result = casmech.analyze(functions, "dynamics", t_end=1.0, output_step=step,
                                 formulation=formulation)
        table(functions, result)
        monkeypatch.undo()
        assert len(result) == round(1.0 / step) + 1
        assert result.metadata["idas_calls"] == 1
        counts[len(result)] = sorted(calls)
    print(f"\n{formulation}: {len(counts[51])} calls: {counts[51]}")
    assert counts[501] == counts[51], counts
