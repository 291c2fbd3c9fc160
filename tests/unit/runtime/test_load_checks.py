"""runtime/load_checks.py: the rows' check of solved friction loads stops at the first row that
is not finite, not unique or not solved, with check_loads' error for that row."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from casmech.errors import AnalysisError
from casmech.runtime.load_checks import LOADS, check_loads, check_rows

JOINTS = [SimpleNamespace(name="a", source=None), SimpleNamespace(name="b", source=None)]


def row(g=(2.0, 3.0), residual=0.0, ratios=((0.1, 0.2), (0.3, 0.1))) -> list[float]:
    """friction_load's outputs for two joints: g, the residual, A row by row."""
    return [*g, residual, *np.ravel(ratios)]


def test_rows_that_hold_pass():
    check_rows([0.0, 0.1], JOINTS, [row(), row(residual=0.5 * LOADS * 3.0)])


@pytest.mark.parametrize(("bad", "words"), [
    (row(ratios=((0.1, 2.0), (0.6, 0.1))), "Painleve"),  # spectral radius about 1.2
    (row(residual=1e-6), "not solved"),
    (row(g=(np.nan, 3.0)), "no finite solution")])
def test_the_first_row_that_fails_stops_with_its_time_and_words(bad, words):
    times = [0.0, 0.1, 0.2]
    with pytest.raises(AnalysisError, match=words) as raised:
        check_rows(times, JOINTS, [row(), bad, bad])
    assert raised.value.context.time == 0.1
    with pytest.raises(AnalysisError) as single:  # the same error as the one-row check's
        check_loads(0.1, JOINTS, np.array(bad))
    assert str(single.value) == str(raised.value)
