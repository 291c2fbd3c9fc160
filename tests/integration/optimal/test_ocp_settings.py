"""IPOPT options and the initial guess of `ocp:` from YAML and the command line: a warm start
from a previous `casmech optimize` result reads back its states and controls, and converges
in a few iterations to the same optimum."""

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import casmech
from casmech.cli import main
from casmech.errors import UsageError
from casmech.io.csv import write_csv
from casmech.optimal import warm_start
from casmech.optimal.ocp import OCP, from_block, joints_of, results_table, solve
from tests.conftest import MODELS

CART_POLE = MODELS / "ocp_cart_pole_swing_up.yaml"
PENDULUM = MODELS / "ocp_pendulum_swing_up.yaml"


def _with(path: Path, folder: Path, lines: str) -> Path:
    """A copy of the model in `folder` with `lines` added to its ocp: block."""
    text = path.read_text().replace("ocp:\n", "ocp:\n" + lines + "\n", 1)
    copy = folder / path.name
    copy.write_text(text)
    return copy


def _printed(out: str) -> tuple[float, int]:
    found = re.search(r"objective ([-\d.e+]+), IPOPT Solve_Succeeded in (\d+) iterations", out)
    assert found, out
    return float(found.group(1)), int(found.group(2))


@pytest.mark.parametrize("formulation", ["joints", "bodies"])
def test_a_previous_result_reads_back_as_its_states_and_controls(tmp_path, formulation):
    """results.csv and controls.csv as `casmech optimize` writes them give back the
    solution's nodes (joint states: the pole's angle through pi, continued across it) and
    controls."""
    model = casmech.load(CART_POLE)
    problem, _ = from_block(model.ocp)
    problem = OCP(**{**problem.__dict__, "formulation": formulation, "intervals": 12})
    solution = solve(model, problem, "collocation")
    names, values = results_table(model, problem, solution)
    write_csv(tmp_path / "results.csv", names, values)
    write_csv(tmp_path / "controls.csv", ["t", "track.force"],
              np.column_stack([solution.times[:-1], solution.u]))
    files = (str(tmp_path / "results.csv"), str(tmp_path / "controls.csv"))
    previous = warm_start.solution(model, OCP(**{**problem.__dict__, "guess_file": files}),
                                   joints_of(model, problem))
    assert previous.formulation == solution.formulation
    np.testing.assert_allclose(previous.u, solution.u, rtol=0, atol=1e-12)  # 17 digits
    if formulation == "joints":
        # the joint states go through the bodies' poses and rates (a rotation and its
        # angle: roundoff, measured 4e-15)
        np.testing.assert_allclose(previous.x, solution.x, rtol=0, atol=1e-10)
        return
    # body coordinates: q and r_dot as written; p_dot up to its part along p, which the
    # angular velocity omega = 2 E(p) p_dot does not hold (the optimum's drift of |p|,
    # 2e-3 here): the same omega, to roundoff
    n, bodies = solution.x.shape[1] // 2, len(model.bodies)
    np.testing.assert_allclose(previous.x[:, :n + 3 * bodies], solution.x[:, :n + 3 * bodies],
                               rtol=0, atol=1e-12)
    for row, given in zip(previous.x, solution.x, strict=True):
        for k in range(bodies):
            p = given[3 * bodies + 4 * k:3 * bodies + 4 * k + 4]
            skew = np.array([[0, -p[3], p[2]], [p[3], 0, -p[1]], [-p[2], p[1], 0]])
            e_matrix = np.column_stack([-p[1:], skew + p[0] * np.eye(3)])  # [-e, e~ + e0 I]
            rates = [x[n + 3 * bodies + 4 * k:n + 3 * bodies + 4 * k + 4] for x in (row, given)]
            np.testing.assert_allclose(e_matrix @ rates[0], e_matrix @ rates[1], rtol=0,
                                       atol=1e-12)


def test_a_warm_start_from_the_optimum_converges_at_once(tmp_path, capsys):
    """`initial_guess: {file: ...}` on the previous run's results: the same optimum in a
    few iterations (measured 22 from the simulated guess, 6 warm)."""
    assert main(["optimize", str(CART_POLE), "--out", str(tmp_path / "first")]) == 0
    cold, cold_iterations = _printed(capsys.readouterr().out)
    model = _with(CART_POLE, tmp_path, "  initial_guess: {file: first/results.csv}")
    assert main(["optimize", str(model), "--out", str(tmp_path / "second")]) == 0
    warm, iterations = _printed(capsys.readouterr().out)
    # the same local optimum, to IPOPT's tolerance (tol 1e-10)
    np.testing.assert_allclose(warm, cold, rtol=1e-9, atol=0)
    assert iterations <= 8 < cold_iterations


def test_ipopt_options_from_yaml_and_the_command_line(tmp_path, capsys):
    """solver: {max_iter: 3} stops IPOPT before the optimum (a located failure, not a
    result); --option max_iter=500 overrides the block; a bad --option is a usage error."""
    shutil.copy(PENDULUM, tmp_path / "source.yaml")
    model = _with(PENDULUM, tmp_path, "  solver: {max_iter: 3, print_level: 0}")
    assert casmech.load(model).ocp.solver == (("max_iter", 3), ("print_level", 0))
    assert main(["optimize", str(model), "--out", str(tmp_path / "out")]) != 0
    assert "Maximum_Iterations_Exceeded" in capsys.readouterr().err
    assert main(["optimize", str(model), "--out", str(tmp_path / "out"),
                 "--option", "max_iter=500"]) == 0
    _printed(capsys.readouterr().out)
    for bad, message in (("max_iter=many", "expected an integer"),
                         ("max_itr=3", "did you mean 'max_iter'"),
                         ("mu_strategy=fast", "monotone | adaptive")):
        assert main(["optimize", str(model), "--option", bad]) != 0
        assert message in capsys.readouterr().err


def test_a_guess_file_that_is_not_a_result_is_a_usage_error(tmp_path):
    (tmp_path / "results.csv").write_text("t,x\n0,1\n1,2\n")
    (tmp_path / "controls.csv").write_text("t,pivot.torque\n0,1\n1,2\n")
    model = casmech.load(_with(PENDULUM, tmp_path, "  initial_guess: {file: results.csv}"))
    problem, transcription = from_block(model.ocp)
    with pytest.raises(UsageError, match="has no column bar.x"):
        solve(model, problem, transcription)


@pytest.mark.slow
def test_a_warm_start_on_a_finer_grid_reaches_its_cold_optimum(tmp_path, capsys):
    """The 25-interval optimum interpolated to 40 intervals: the 40-interval problem's own
    optimum (its cold start's), in fewer iterations (measured 8 against 25)."""
    assert main(["optimize", str(CART_POLE), "--out", str(tmp_path / "first")]) == 0
    capsys.readouterr()
    assert main(["optimize", str(CART_POLE), "--out", str(tmp_path / "cold"),
                 "--intervals", "40"]) == 0
    cold, cold_iterations = _printed(capsys.readouterr().out)
    model = _with(CART_POLE, tmp_path, "  initial_guess: {file: first/results.csv}")
    assert main(["optimize", str(model), "--out", str(tmp_path / "warm"),
                 "--intervals", "40"]) == 0
    warm, iterations = _printed(capsys.readouterr().out)
    np.testing.assert_allclose(warm, cold, rtol=1e-9, atol=0)  # IPOPT's tol 1e-10
    assert iterations < cold_iterations
