"""runtime.solver_messages: the solvers' own stderr lines are kept for the metadata, every other
line passes through unchanged, whatever fragments the text arrives in."""

import io
import json
import subprocess
import sys

import casadi as ca
import numpy as np
import pytest

from casmech.runtime.solver_messages import _Filter, collected, without_input_dumps
from tests.conftest import ROOT
from tests.validation.runtime.test_joint_dynamics import BLOWING_UP

WARNING = 'CasADi - 2026-11-24 11:53:57 WARNING("LDL factorization has zeros in D") [x.cpp:1]\n'
SUNDIALS = "At t = 0.3 and h = 4.7e-14, the corrector convergence failed repeatedly.\n"
OTHER = "\r 50%|#####     | 0.5/1 s\rCasting a line\nCa\n"


def fragments(text: str, size: int) -> list[str]:
    return [text[k:k + size] for k in range(0, len(text), size)]


def test_solver_lines_are_kept_and_the_rest_passes_through():
    for size in (1, 3, 7, 1000):  # CasADi writes a warning in ~20 pieces
        target, kept = io.StringIO(), []
        stream = _Filter(target, kept)
        for piece in fragments(OTHER + WARNING + SUNDIALS + "tail", size):
            stream.write(piece)
        stream.close_line()
        assert target.getvalue() == OTHER + "tail", size
        assert kept == [WARNING.rstrip("\n"), SUNDIALS.rstrip("\n")]
        assert stream.count == 2


def test_collected_restores_stderr():
    before = sys.stderr
    with collected([]) as stream:
        assert sys.stderr is stream
    assert sys.stderr is before


def failing_run(tmp_path, text: str) -> list[str]:
    """`casmech run` (r-p, interpreted) of a model whose run fails at t = 0.3: its stderr holds
    casmech's own lines only; the solver lines the metadata kept."""
    model = tmp_path / "blowing_up.yaml"
    model.write_text(text)
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, "-m", "casmech.cli", "run", str(model), "--out",
                          str(out), "--formulation", "rp", "--mode", "interpreted"],
                         capture_output=True, text=True, timeout=300,
                         env={"PYTHONPATH": str(ROOT / "src"), "PATH": "/usr/bin:/bin"})
    assert run.returncode == 3, run.stderr
    assert "CasADi - " not in run.stderr and "At t = " not in run.stderr
    assert "casmech: analysis failed at t = 0.3" in run.stderr
    kept = json.loads((out / "metadata.json").read_text())["result"]
    assert kept["solver_message_count"] == len(kept["solver_messages"])
    return kept["solver_messages"]


def test_a_failing_run_prints_only_casmechs_lines(tmp_path):
    """A torque 1 / (0.305 - t): IDAS's corrector fails as it diverges; its lines are kept in
    the metadata, not printed."""
    text = BLOWING_UP.replace("(0.305 - t)**3", "(0.305 - t)")
    assert text != BLOWING_UP
    kept = failing_run(tmp_path, text)
    assert len(kept) >= 2  # IDAS's corrector failures (measured: 2)
    assert all(line.startswith("At t = ") for line in kept)


@pytest.mark.slow
def test_a_failing_run_through_the_fallback_prints_only_casmechs_lines(tmp_path):
    """The r-p run of a torque 1 / (0.305 - t)^3 fails through IDAS and the Runge-Kutta
    fallback, whose solvers print ~20 lines (CasADi's warnings among them); stderr holds
    casmech's own, the metadata the rest."""
    kept = failing_run(tmp_path, BLOWING_UP)
    assert len(kept) >= 2  # IDAS's and the fallback's (measured: 26)
    assert any(line.startswith("At t = ") for line in kept)
    assert any(line.startswith("CasADi - ") for line in kept)


def test_a_failing_mapped_calls_input_dump_is_dropped_and_other_text_kept(capsys):
    """CasADi prints the inputs of a Function whose mapped evaluation raises; within
    without_input_dumps that dump is dropped, the error still raised, other text passed on."""
    x = ca.MX.sym("x", 2, 2)
    solve = ca.Function("solve", [x], [ca.solve(x, ca.DM.ones(2), "csparse")]).map(2)
    with pytest.raises(RuntimeError, match="singular"):
        with without_input_dumps():
            print("before", file=sys.stderr)
            solve(np.ones((2, 4)))  # singular matrices
    assert capsys.readouterr().err == "before\n"
    with without_input_dumps():
        print("kept", file=sys.stderr)
        solve(np.hstack([np.eye(2), np.eye(2)]))
    assert capsys.readouterr().err == "kept\n"
