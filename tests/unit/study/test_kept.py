"""casmech.study.kept: the numbers kept per run, against closed forms of sampled functions."""

import numpy as np
import pytest

from casmech.study import kept
from casmech.study.design import StudyError

T = np.linspace(0.0, 2.0, 201)
NAMES = ["t", "x", "v"]
OMEGA = 3.0
TABLE = np.column_stack([T, np.cos(OMEGA * T), -OMEGA * np.sin(OMEGA * T)])


def value(text):
    return kept.parse(text).value(NAMES, TABLE)


def test_crossing_of_a_cosine():
    # x = cos(3t) first crosses zero at pi/6; linear interpolation between rows h = 0.01
    # apart misses a root of a sinusoid by at most omega^2 h^3 / (36 sqrt 3) = 1.4e-7 s
    np.testing.assert_allclose(value("crossing(x)"), np.pi / 6, rtol=0, atol=2e-6)
    # v starts at exactly 0: the start is not a crossing; v next changes sign at pi/3
    np.testing.assert_allclose(value("crossing(v)"), np.pi / 3, rtol=0, atol=2e-6)


def test_reductions():
    np.testing.assert_allclose(value("max(v)"), OMEGA, rtol=1e-3, atol=0)  # rows miss the peak
    assert value("min(x)") == np.min(TABLE[:, 1])
    assert value("final(x)") == TABLE[-1, 1]
    # trapezoid error of cos(3t) over [0, 2] with h = 0.01: h^2/12 * |x'(2) - x'(0)| < 2e-5
    np.testing.assert_allclose(value("integral(x)"), np.sin(6.0) / 3, rtol=0, atol=2e-5)
    # linear interpolation at 0.505 between rows: error <= omega^2 h^2 / 8 ~ 1.2e-4
    np.testing.assert_allclose(value("x@0.505"), np.cos(1.515), rtol=0, atol=1.2e-4)


def test_no_rows_and_no_crossing_are_nan():
    assert np.isnan(kept.parse("max(x)").value(NAMES, np.zeros((0, 3))))
    flat = TABLE.copy()
    flat[:, 1] = 1.0
    assert np.isnan(kept.parse("crossing(x)").value(NAMES, flat))


@pytest.mark.parametrize("text, message", [("maximum(x)", "did you mean 'max'"),
                                            ("x@soon", "not a time"), ("x", "COLUMN@T")])
def test_bad_forms(text, message):
    with pytest.raises(StudyError) as error:
        kept.parse(text)
    assert message in f"{error.value} {error.value.hint}"


def test_check_names_the_column():
    with pytest.raises(StudyError) as error:
        kept.check(kept.parse("max(bar.zz)"), ["t", "bar.z"], 1.0)
    assert error.value.hint == "did you mean 'bar.z'?"
    with pytest.raises(StudyError, match="outside"):
        kept.check(kept.parse("bar.z@2"), ["t", "bar.z"], 1.0)
