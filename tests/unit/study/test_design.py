"""casmech.study.design: grid axes, sampled parameters, the runs' order."""

import numpy as np
import pytest

from casmech.study.design import Study, StudyError, distribution, grid_values


def test_grid_forms():
    assert grid_values("0.8:1.2:5") == pytest.approx([0.8, 0.9, 1.0, 1.1, 1.2], rel=0, abs=1e-15)
    assert grid_values("100,200,400") == (100.0, 200.0, 400.0)
    assert grid_values([1, 2.5]) == (1.0, 2.5)
    assert grid_values(3) == (3.0,)


@pytest.mark.parametrize("text", ["1:2", "1:2:0", "1:2:2.5", "a,b", "1:2:1", "", "1:x:3"])
def test_bad_grid(text):
    with pytest.raises(StudyError):
        grid_values(text)


def test_distributions_checked():
    assert distribution("normal", "2,0.05") == ("normal", 2.0, 0.05)
    with pytest.raises(StudyError, match="negative") as error:
        distribution("normal", "2,-0.05")
    assert error.value.code == "E409"
    with pytest.raises(StudyError, match="above"):
        distribution("uniform", [0.3, 0.1])
    with pytest.raises(StudyError, match="two numbers"):
        distribution("uniform", "0.1")


def test_grid_product_in_order():
    study = Study({"a": (1.0, 2.0), "b": (10.0, 20.0, 30.0)})
    points = study.points()
    assert study.size() == len(points) == 6
    assert points[:4] == [{"a": 1.0, "b": 10.0}, {"a": 1.0, "b": 20.0}, {"a": 1.0, "b": 30.0},
                          {"a": 2.0, "b": 10.0}]


def test_samples_follow_the_seed_and_the_distribution():
    study = Study(distributions={"m": ("normal", 2.0, 0.05), "c": ("uniform", 0.1, 0.3)},
                  samples=4000, seed=7)
    points = study.points()
    assert points == Study(distributions=dict(study.distributions), samples=4000,
                           seed=7).points()
    m = np.array([p["m"] for p in points])
    c = np.array([p["c"] for p in points])
    # 5 standard errors of the sample mean (sigma / sqrt(n)) and of the sample std
    np.testing.assert_allclose(m.mean(), 2.0, rtol=0, atol=5 * 0.05 / np.sqrt(4000))
    np.testing.assert_allclose(m.std(ddof=1), 0.05, rtol=5 / np.sqrt(2 * 3999), atol=0)
    assert c.min() >= 0.1 and c.max() <= 0.3


def test_grid_times_samples():
    study = Study({"L": (1.0, 2.0)}, {"m": ("uniform", 1.0, 2.0)}, samples=3, seed=1)
    points = study.points()
    assert len(points) == 6
    assert [p["m"] for p in points[:3]] == [p["m"] for p in points[3:]]


@pytest.mark.parametrize("kwargs, message", [
    ({"distributions": {"m": ("normal", 1.0, 0.1)}}, "sample count"),
    ({"samples": 5}, "no parameter to sample"),
    ({}, "names no parameter"),
    ({"grid": {"m": (1.0,)}, "seed": -1}, "seed must be >= 0"),
    ({"grid": {"m": (1.0,)}, "distributions": {"m": ("normal", 1.0, 0.1)}, "samples": 2},
     "both"),
])
def test_inconsistent_study(kwargs, message):
    with pytest.raises(StudyError, match=message):
        Study(**kwargs)
