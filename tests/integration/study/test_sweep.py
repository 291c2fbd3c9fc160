"""casmech.sweep end to end in this process (workers=0): closed forms of the physics at every
point of a grid and of a sampled study, failed runs recorded while the study goes on."""

import math

import numpy as np
import pytest

import casmech
from casmech.backends import codegen
from tests.helpers.study import FOUR_BAR, PENDULUM, SPRING_MASS, G


def test_pendulum_period_at_every_grid_point():
    """The study of pendulum.yaml's `study:` block: L = 0.5, 1, 1.5, 2."""
    table = casmech.sweep(PENDULUM, workers=0)
    assert list(table["L"]) == [0.5, 1.0, 1.5, 2.0]
    assert set(table["status"]) == {"complete"}
    L, m, J, theta0 = table["L"].to_numpy(), 1.0, 0.01, 0.01
    period = 2 * np.pi * np.sqrt((J + m * L**2) / (m * G * L)) * (1 + theta0**2 / 16)
    # the release amplitude's correction is included (its next term ~theta0^4 ~ 1e-8); the
    # crossing's linear interpolation between rows h = 0.01 s apart errs by at most
    # omega^2 h^3 / (36 sqrt 3) = 3e-7 s at L = 0.5 (kept.py), 1.2e-6 s on 4 crossings; the
    # integrator (rtol 1e-10) by far less
    np.testing.assert_allclose(4 * table["crossing(bob.y)"], period, rtol=0, atol=2e-6)


def test_sampled_mass_gives_the_predicted_frequency_distribution():
    n, mean, sigma, k = 40, 2.0, 0.1, 200.0
    table = casmech.sweep(SPRING_MASS, samples=n, normal={"m": (mean, sigma)}, seed=3,
                          keep=["crossing(block.z)"], workers=0)
    frequency = 1 / (4 * table["crossing(block.z)"].to_numpy())
    m = table["m"].to_numpy()
    # each run: f = sqrt(k/m) / (2 pi); the crossing interpolated between rows h = 5 ms apart
    # errs by at most omega^2 h^3 / (36 sqrt 3) ~ 2e-7 s of T/4 ~ 0.157 s: 1.3e-6 relative
    np.testing.assert_allclose(frequency, np.sqrt(k / m) / (2 * np.pi), rtol=3e-6, atol=0)
    # the distribution: moments of f(m), m ~ N(mean, sigma), by Gauss-Hermite quadrature;
    # the sample mean within 4 standard errors, the sample std within 4 of its standard errors
    x, w = np.polynomial.hermite_e.hermegauss(40)
    f = np.sqrt(k / (mean + sigma * x)) / (2 * np.pi)
    f_mean = w @ f / w.sum()
    f_std = math.sqrt(w @ (f - f_mean) ** 2 / w.sum())
    np.testing.assert_allclose(frequency.mean(), f_mean, rtol=0, atol=4 * f_std / math.sqrt(n))
    np.testing.assert_allclose(frequency.std(ddof=1), f_std, rtol=4 / math.sqrt(2 * (n - 1)),
                               atol=0)


def test_failed_runs_are_recorded_and_the_study_goes_on():
    """a = 1.9 breaks the four-bar's Grashof condition: assembly fails mid-run (t ~ 0.2);
    m = -1 is a model error at load; the runs around them complete."""
    table = casmech.sweep(FOUR_BAR, grid={"a": [0.5, 1.9, 0.6]}, keep=["max(crank.wz)"],
                          workers=0, t_end=0.4)
    assert list(table["status"]) == ["complete", "failed", "complete"]
    assert "analysis failed at t =" in table["reason"][1]
    assert table["reason"][0] == table["reason"][2] == ""
    # the crank turns at omega = pi: the rows before the failure still give max(crank.wz)
    np.testing.assert_allclose(table["max(crank.wz)"], np.pi, rtol=1e-12, atol=0)
    table = casmech.sweep(FOUR_BAR, grid={"m": "-1,1"}, keep=["final(crank.wz)"], workers=0,
                          t_end=0.1)
    assert list(table["status"]) == ["failed", "complete"]
    assert "E400" in table["reason"][0] and np.isnan(table["final(crank.wz)"][0])


def test_runs_as_one_run_would():
    """A sweep's point gives the numbers `casmech run --set` gives."""
    table = casmech.sweep(PENDULUM, grid={"L": [1.3]}, keep=["max(bob.z)", "bob.y@0.25"],
                          workers=0)
    functions = casmech.compile(casmech.load(PENDULUM, {"L": "1.3"}))
    names, values = casmech.results_table(functions, casmech.analyze(functions))
    z, y = values[:, names.index("bob.z")], values[:, names.index("bob.y")]
    assert table["max(bob.z)"][0] == z.max()
    np.testing.assert_allclose(table["bob.y@0.25"][0], y[25], rtol=1e-14, atol=0)  # a row


@pytest.mark.parametrize("given, message", [
    ({"grid": {"Lx": [1.0]}}, "unknown parameter 'Lx'"),
    ({"grid": {"bob": [1.0]}}, "'bob' is a body, not a parameter"),
    ({"keep": ["max(bob.zz)"]}, "did you mean 'bob.z'?"),
])
def test_usage_errors(given, message):
    with pytest.raises(casmech.UsageError) as error:
        casmech.sweep(PENDULUM, workers=0, **given)
    assert message in str(error.value)


def test_no_library_is_built(tmp_path, monkeypatch):
    """A small study runs interpreted (mode auto below COMPILE_RUNS): the compiled-model cache
    stays empty however many values are run."""
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))
    casmech.sweep(PENDULUM, grid={"L": [0.7, 0.8, 0.9]}, workers=0)
    assert not (tmp_path / "cache").exists() or not any((tmp_path / "cache").rglob("*.so"))


@pytest.mark.skipif(not codegen.available(), reason="no C compiler")
def test_compiled_study_builds_one_library_for_every_value(tmp_path, monkeypatch, quick_builds):
    """mode compiled: the pendulum's parametric library is built once, before the runs, and
    every L is bound to it; the kept outputs equal the interpreted study's."""
    from tests.helpers.codegen import model_libraries

    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))
    grid = {"L": [0.5, 1.0, 2.0]}
    compiled = casmech.sweep(PENDULUM, grid=grid, workers=0, mode="compiled")
    assert len(model_libraries(tmp_path / "cache")) == 1
    interpreted = casmech.sweep(PENDULUM, grid=grid, workers=0, mode="interpreted")
    # the same equations, C against the SX interpreter, at rtol 1e-10: the crossings agree to
    # far below the output step's interpolation error
    np.testing.assert_allclose(compiled["crossing(bob.y)"], interpreted["crossing(bob.y)"],
                               rtol=0, atol=1e-9)
    assert set(compiled["status"]) == {"complete"}


def test_a_loaded_model_sweeps_as_its_file():
    by_path = casmech.sweep(PENDULUM, grid={"L": [0.9, 1.1]}, workers=0)
    by_model = casmech.sweep(casmech.load(PENDULUM), grid={"L": [0.9, 1.1]}, workers=0)
    assert list(by_model["crossing(bob.y)"]) == list(by_path["crossing(bob.y)"])


def test_event_times_kept_at_every_grid_point(tmp_path):
    """event(NAME): the pendulum released at 1 rad reaches the bottom (bob.y falls through 0) at
    the exact quarter period sqrt((J + m L^2) / (m g L)) K(sin^2(theta0 / 2)) for each L."""
    from scipy.special import ellipk

    model = tmp_path / "pendulum.yaml"
    model.write_text(PENDULUM.read_text().replace("study:", "events:\n  - {name: bottom, "
                                                  "when: bob.y, direction: falling}\nstudy:"))
    table = casmech.sweep(model, grid={"L": [0.5, 1.0, 2.0]}, keep=["event(bottom)"],
                          workers=0, overrides={"theta0": "1.0"})
    L, m, J = table["L"].to_numpy(), 1.0, 0.01
    quarter = np.sqrt((J + m * L**2) / (m * G * L)) * ellipk(np.sin(0.5) ** 2)
    # located to the run's tolerance (rtol 1e-10), not to the 0.01 s output grid
    np.testing.assert_allclose(table["event(bottom)"], quarter, rtol=0, atol=1e-8)
    with pytest.raises(casmech.errors.UsageError, match="no event 'botom'"):
        casmech.sweep(model, grid={"L": [1.0]}, keep=["event(botom)"], workers=0)
