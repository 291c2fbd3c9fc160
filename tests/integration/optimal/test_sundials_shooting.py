"""Multiple shooting with CVODES and IDAS (optimal/shooting.py SundialsShooting): the same
optimum as a fine Radau collocation of the same problem, the nodes replayed by DOP853, and
the settings it refuses."""

from dataclasses import replace

import numpy as np
import pytest

import casmech
from casmech.cli import main
from casmech.errors import UsageError
from casmech.optimal.controls import Control
from casmech.optimal.ocp import OCP, columns_at, from_block, replay, solve
from tests.conftest import MODELS


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))


def _gallery(name: str):
    model = casmech.load(MODELS / f"{name}.yaml")
    return model, from_block(model.ocp)[0]


def _same_optimum(name: str):
    """CVODES shooting against Radau 3 collocation with 8 elements per interval: both
    transcribe the same continuous problem (piecewise-constant controls), CVODES to its
    tolerances (1e-10), the collocation to its local error O((h/8)^5)."""
    model, problem = _gallery(name)
    shooting = solve(model, replace(problem, integrator="cvodes"), "shooting")
    fine = solve(model, replace(problem, elements=8), "collocation")
    coarse = solve(model, problem, "collocation")
    assert shooting.formulation == "joints" and shooting.status == "Solve_Succeeded"
    # the fine collocation's cost error: ~1/32 of its difference from 4 elements (order 5),
    # measured 1e-9 relative; 1e-7 lies above it and below one element's 2e-5 (cart-pole)
    np.testing.assert_allclose(shooting.objective, fine.objective, rtol=1e-7, atol=0)
    # the controls: the same optimum (measured 1e-6 N m on the pendulum)
    np.testing.assert_allclose(shooting.u, fine.u, rtol=0, atol=1e-4)
    # each interval's end is CVODES's at rtol 1e-10: DOP853 from each node meets the next
    replayed = replay(model, problem, shooting)
    np.testing.assert_allclose(replayed, shooting.x, rtol=0, atol=1e-7)
    return shooting, fine, coarse


def test_cvodes_shooting_has_the_pendulums_optimum():
    _same_optimum("ocp_pendulum_swing_up")


@pytest.mark.slow
def test_cvodes_shooting_has_the_cart_poles_optimum():
    shooting, fine, coarse = _same_optimum("ocp_cart_pole_swing_up")
    # the test can tell: one element per interval is off by more than the tolerance
    assert abs(coarse.objective - fine.objective) > 1e-6 * fine.objective


def test_an_integrator_is_refused_where_it_integrates_nothing():
    model, problem = _gallery("ocp_pendulum_swing_up")
    with pytest.raises(UsageError, match="use transcription shooting"):
        solve(model, replace(problem, integrator="cvodes"), "collocation")
    with pytest.raises(UsageError, match="integrator cvodes"):
        solve(model, replace(problem, integrator="cvodes", formulation="bodies"), "shooting")
    with pytest.raises(UsageError, match="rk4, cvodes, idas"):
        solve(model, replace(problem, integrator="cvode"), "shooting")


def test_the_command_line_takes_the_integrator(tmp_path, capsys):
    """casmech optimize --transcription shooting --integrator cvodes: the pendulum's optimum
    on 10 intervals, the same as the API's."""
    path = MODELS / "ocp_pendulum_swing_up.yaml"
    code = main(["optimize", str(path), "--transcription", "shooting", "--integrator",
                 "cvodes", "--intervals", "10", "--out", str(tmp_path)])
    assert code == 0
    printed = capsys.readouterr().out
    model, problem = _gallery("ocp_pendulum_swing_up")
    expected = solve(model, replace(problem, intervals=10, integrator="cvodes"), "shooting")
    assert f"objective {expected.objective:.10g}" in printed
    assert (tmp_path / "results.csv").exists()


@pytest.mark.slow
def test_idas_on_a_tree_takes_cvodes_optimum():
    """IDAS integrates a tree's ODE as CVODES does: the same NLP optimum to the integrators'
    tolerances (rtol 1e-10)."""
    model, problem = _gallery("ocp_pendulum_swing_up")
    problem = replace(problem, intervals=10)
    cvodes = solve(model, replace(problem, integrator="cvodes"), "shooting")
    idas = solve(model, replace(problem, integrator="idas"), "shooting")
    # two integrators of one ODE at rtol 1e-10: measured 1e-9 relative
    np.testing.assert_allclose(idas.objective, cvodes.objective, rtol=1e-7, atol=0)
    np.testing.assert_allclose(idas.u, cvodes.u, rtol=0, atol=1e-5)  # N m, as above



@pytest.mark.slow
def test_cvodes_shooting_on_a_loop_has_the_fine_collocations_optimum():
    """A four-bar (one loop, the tree's quaternion among the coordinates) moved rest to rest
    by its crank: CVODES on the joint ODE with the closure multipliers solved inside, the
    nodes projected onto the closure rows, reaches the optimum of a Radau collocation with
    8 elements per interval; the loop's rows hold at the nodes and DOP853 from each node
    meets the next."""
    text = (MODELS / "four_bar.yaml").read_text().replace(
        "    driver:\n      angle: omega * t\n", "")
    model = casmech.loads(text)
    problem = OCP([Control("crank_pivot", "torque", -50, 50)], horizon=1.0, intervals=5,
                  terminal={"crank_pivot.angle": 0.5, "crank_pivot.angle_dot": 0.0},
                  guess=[0.5], formulation="joints")
    shooting = solve(model, replace(problem, integrator="cvodes"), "shooting")
    fine = solve(model, replace(problem, elements=8), "collocation")
    # as _same_optimum (measured 1e-10 relative; one element per interval: 7.5e-7)
    np.testing.assert_allclose(shooting.objective, fine.objective, rtol=1e-7, atol=0)
    # DOP853 from each node: CVODES's tolerances plus the projection (measured 7e-10)
    np.testing.assert_allclose(replay(model, problem, shooting), shooting.x, rtol=0,
                               atol=1e-7)
    violation = columns_at(model, problem, shooting, ["constraint_violation"])[:, 0]
    assert violation.max() <= 1e-10  # the loop's rows, imposed at every node


@pytest.mark.parametrize("transcription, integrator, words", [
    ("shooting", "cvode", ("cvodes",)),  # misspelt: the values it takes
    ("collocation", "cvodes", ("E409", "transcription: shooting")),  # no integrator there
], ids=["misspelt", "with_collocation"])
def test_a_wrong_integrator_is_located(tmp_path, transcription, integrator, words):
    text = (MODELS / "ocp_pendulum_swing_up.yaml").read_text().replace(
        "  transcription: collocation\n",
        f"  transcription: {transcription}\n  integrator: {integrator}\n")
    path = tmp_path / "model.yaml"
    path.write_text(text)
    with pytest.raises(casmech.ModelError) as error:
        casmech.load(path)
    line = text.splitlines().index(f"  integrator: {integrator}") + 1
    assert f"model.yaml:{line}:" in str(error.value)
    assert all(word in str(error.value) for word in words)
