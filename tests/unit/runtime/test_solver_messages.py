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


def test_a_failing_run_prints_only_casmechs_lines(tmp_path):
    """The r-p run of a torque that blows up fails through IDAS and the Runge-Kutta fallback,
    whose solvers printed ~20 lines; now stderr holds casmech's own, the metadata the rest."""
    model = tmp_path / "blowing_up.yaml"
    model.write_text(BLOWING_UP)
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, "-m", "casmech.cli", "run", str(model), "--out",
                          str(out), "--formulation", "rp", "--mode", "interpreted"],
                         capture_output=True, text=True, timeout=300,
                         env={"PYTHONPATH": str(ROOT / "src"), "PATH": "/usr/bin:/bin"})
    assert run.returncode == 3, run.stderr
    assert "CasADi - " not in run.stderr and "At t = " not in run.stderr
    assert "casmech: analysis failed at t = 0.3" in run.stderr
    metadata = json.loads((out / "metadata.json").read_text())
    kept = metadata["result"]
    assert kept["solver_message_count"] >= 2  # IDAS's and the fallback's (measured: 26)
    assert any(line.startswith("At t = ") for line in kept["solver_messages"])


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
