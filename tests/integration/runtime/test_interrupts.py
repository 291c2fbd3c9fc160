"""Cancelling a run (casmech.runtime.cancel, casmech.runtime.interrupts): a signal or a token
ends an analysis as an Interrupted carrying the rows computed so far, within a solver call at
once and between calls at the driver's next poll; a run whose rows are all computed is
complete; `casmech run` ends within 0.5 s of SIGINT/SIGTERM, rows and metadata written (more
end-to-end runs in tests/integration/test_hostile.py)."""

import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import casmech
from casmech.errors import AnalysisError, CasmechError, Interrupted
from casmech.runtime import interrupts
from casmech.runtime.cancel import CancelToken
from tests.conftest import MODELS, ROOT


def test_interrupted_is_an_analysis_error_and_a_keyboard_interrupt():
    error = Interrupted(signal.SIGTERM)
    assert isinstance(error, AnalysisError) and isinstance(error, KeyboardInterrupt)
    assert isinstance(error, CasmechError)
    assert (error.exit_code, error.signal_name, str(error)) == (143, "SIGTERM",
                                                                 "interrupted by SIGTERM")
    assert Interrupted(signal.SIGINT).exit_code == 130


def test_check_turns_casadis_keyboard_interrupt_back():
    interrupts.check(RuntimeError("integrator failed"))  # a real failure: nothing to raise
    with pytest.raises(Interrupted):
        interrupts.check(RuntimeError("rhs failed: KeyboardInterrupt"))


# (model, analysis, options that make the grid several solver calls or blocks)
CHUNKED = [("double_pendulum.yaml", "dynamics", {"joint_chunk": 100}),
           ("double_pendulum.yaml", "dynamics", {"formulation": "rp", "chunk": 100}),
           ("bricard.yaml", "dynamics", {"joint_chunk": 100}),
           ("four_bar.yaml", "kinematics", {"max_block": 64})]


@pytest.mark.parametrize("path, analysis, options", CHUNKED,
                         ids=lambda value: value if isinstance(value, str) else None)
def test_a_signal_between_calls_stops_at_the_next_poll_with_the_rows(path, analysis, options):
    """The signal is raised from the row callback at row 20: outside a solver call, so the run
    stops before its next call; the rows before it come with the error, a prefix of the rows
    of the whole run."""
    functions = casmech.compile(casmech.load(MODELS / path))
    whole = casmech.analyze(functions, analysis, t_end=1.0, output_step=0.001, options=options,
                            progress=lambda t: None)  # with a callback: the same chunks
    seen = []

    def on_row(t):
        seen.append(t)
        if len(seen) == 20:
            signal.raise_signal(signal.SIGINT)

    with interrupts.trap(), pytest.raises(Interrupted) as caught:
        casmech.analyze(functions, analysis, t_end=1.0, output_step=0.001, progress=on_row,
                        options=options)
    partial = caught.value.partial
    assert partial is not None and 20 <= len(partial) < len(whole)
    assert partial.status == "interrupted"
    assert partial.times == whole.times[:len(partial)]
    np.testing.assert_array_equal(partial.q, whole.q[:len(partial)])  # the same rows
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # restored


def test_a_signal_after_the_last_row_leaves_a_complete_run():
    """Every row computed when the signal came: the run is complete, not interrupted."""
    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))

    def on_row(t):
        if t >= 1.0 - 1e-12:
            signal.raise_signal(signal.SIGTERM)

    with interrupts.trap():
        result = casmech.analyze(functions, t_end=1.0, output_step=0.01, progress=on_row)
    assert result.status == "complete" and result.times[-1] == 1.0 and len(result) == 101


def test_a_token_cancelled_by_the_caller_stops_the_run():
    """casmech.analyze(token=...): cancel() from a callback (or another thread) stops the run
    at the next poll, with its rows."""
    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    token = CancelToken()
    with pytest.raises(Interrupted) as caught:
        casmech.analyze(functions, t_end=1.0, output_step=0.001, token=token,
                        progress=lambda t: t >= 0.05 and token.cancel(signal.SIGTERM),
                        options={"joint_chunk": 100})
    assert caught.value.signum == signal.SIGTERM
    assert 50 <= len(caught.value.partial) <= 101


@pytest.mark.parametrize("path, analysis, options", [
    ("double_pendulum.yaml", "dynamics", {"formulation": "joint"}),
    ("double_pendulum.yaml", "dynamics", {"formulation": "rp"}),
    ("double_pendulum.yaml", "dynamics", {"formulation": "romega", "stabilization": "projection"}),
    ("double_pendulum.yaml", "dynamics", {"formulation": "rp", "fallback.always": True}),
    ("four_bar.yaml", "kinematics", None),
    ("four_bar.yaml", "inverse_dynamics", None),
    ("bushing_mount.yaml", "statics", None),
    ("bushing_mount.yaml", "modal", None),
], ids=lambda value: value if isinstance(value, str) else None)
def test_every_analysis_polls_the_token(path, analysis, options):
    """A token cancelled before the run: every analysis and formulation stops at its first
    poll (none runs to its end unasked)."""
    functions = casmech.compile(casmech.load(MODELS / path))
    token = CancelToken()
    token.cancel(signal.SIGTERM)
    with pytest.raises(Interrupted) as caught:
        casmech.analyze(functions, analysis, t_end=1.0, options=options, token=token)
    assert caught.value.signum == signal.SIGTERM


def test_ctrl_c_in_the_api_keeps_the_rows():
    """Without trap() (a Python caller), Ctrl-C during casmech.analyze raises Interrupted, a
    KeyboardInterrupt, with the rows; Python's handler is back afterwards."""
    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))

    def on_row(t):  # Ctrl-C pressed again and again: a Python caller's process is not ended
        if t >= 0.05:
            signal.raise_signal(signal.SIGINT)

    with pytest.raises(KeyboardInterrupt) as caught:
        casmech.analyze(functions, t_end=1.0, output_step=0.001, progress=on_row,
                        options={"joint_chunk": 100})
    assert isinstance(caught.value, Interrupted) and len(caught.value.partial) >= 50
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_an_analysis_in_another_thread_leaves_the_handler_alone():
    """Only the main thread installs casmech's Ctrl-C handler: a run in another thread
    (the guard's install refused there) completes, its token the running one, and neither
    installs a handler nor leaves one behind."""
    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    seen, failed = [], []

    def on_row(t):
        seen.append((signal.getsignal(signal.SIGINT), bool(interrupts._traps)))

    def run():
        try:
            casmech.analyze(functions, t_end=0.05, progress=on_row)
        except BaseException as error:  # noqa: BLE001 (reported below)
            failed.append(error)

    thread = threading.Thread(target=run)
    thread.start()
    thread.join()
    assert not failed and seen
    assert all(handler is signal.default_int_handler and not traps for handler, traps in seen)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.parametrize("formulation", ["joint", "rp"])
def test_a_signal_stops_an_integrator_call_at_once_and_keeps_its_rows(formulation):
    """One solver call over 2000 output intervals of a bouncing ball (seconds of work): a
    SIGINT 0.5 s into it stops the call within 0.2 s (measured ~1 ms), and the grid points
    the call had finished are kept, the same as those of an uninterrupted run."""
    functions = casmech.compile(casmech.load(MODELS / "bouncing_ball.yaml"))
    options = {"joint_chunk": 100_000, "chunk": 100_000, "formulation": formulation}
    short = casmech.analyze(functions, t_end=2.0, output_step=0.01, options=options,
                            progress=lambda t: None)
    sent = []

    def fire():
        time.sleep(0.5)
        sent.append(time.perf_counter())
        os.kill(os.getpid(), signal.SIGINT)

    threading.Thread(target=fire, daemon=True).start()
    with interrupts.trap(), pytest.raises(Interrupted) as caught:
        casmech.analyze(functions, t_end=200.0, output_step=0.01, options=options,
                        progress=lambda t: None)
    stopped = time.perf_counter() - sent[0]
    partial = caught.value.partial
    assert stopped < 0.2, stopped
    assert len(partial) > 10  # the call's finished grid points, not only the first row
    rows = min(len(partial), len(short) - 1)
    # the same integration up to where either ended (one call from the same start; the short
    # run's last row is where its integrator stopped, not a point it passed): the
    # interrupted call's columns are those an uninterrupted call writes, bit for bit
    np.testing.assert_array_equal(partial.q[:rows], short.q[:rows])


def test_saving_waits_for_the_signal():
    with interrupts.trap():
        with interrupts.saving():
            signal.raise_signal(signal.SIGTERM)  # no raise while writing
        assert interrupts.pending() == signal.SIGTERM
        with pytest.raises(Interrupted):
            interrupts.check()
    assert interrupts.pending() is None


LONG_CONTACT = MODELS / "bouncing_ball.yaml"


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_casmech_run_ends_within_half_a_second_of_the_signal(tmp_path, signum):
    """issue 35 item 8: a long contact model in joint coordinates (output intervals whose
    integration takes long: the chunk of 1000 of them took 31.8 s to act on Ctrl-C), the
    signal 1 s into the analysis: the process ends within 0.5 s, with the rows computed so
    far in results.csv and metadata.json saying interrupted."""
    out = tmp_path / "out"
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "CASMECH_CACHE_DIR": str(tmp_path),
           "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])}
    process = subprocess.Popen(
        [sys.executable, "-m", "casmech.cli", "run", str(LONG_CONTACT), "--out", str(out),
         "--t-end", "100000", "--output-step", "1", "--formulation", "joint"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    meta = out / "metadata.json"
    deadline = time.perf_counter() + 60
    while not (meta.exists() and '"running"' in meta.read_text()):
        assert process.poll() is None and time.perf_counter() < deadline, process.stdout.read()
        time.sleep(0.01)
    time.sleep(1.0)
    process.send_signal(signum)
    sent = time.perf_counter()
    process.wait(timeout=30)
    took = time.perf_counter() - sent
    output = process.stdout.read()
    assert process.returncode == 128 + signum, output
    assert took < 0.5, (took, output)
    record = json.loads(meta.read_text())
    assert record["status"] == "interrupted" and record["signal"] == signal.Signals(signum).name
    from casmech.io.csv import read_csv

    names, values = read_csv(out / "results.csv")
    assert names[0] == "t" and len(values) == record["rows"] > 1
    assert values[0, 0] == 0.0 and (np.diff(values[:, 0]) == 1.0).all()
