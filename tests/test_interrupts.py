"""casmech.runtime.interrupts: a signal during an analysis ends it as an Interrupted carrying the
rows
computed so far (the end-to-end SIGINT/SIGTERM runs are in tests/test_hostile.py)."""

import signal

import pytest

import casmech
from casmech.errors import AnalysisError, CasmechError, Interrupted
from casmech.runtime import interrupts
from tests.conftest import MODELS


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


@pytest.mark.parametrize("path, analysis", [("double_pendulum.yaml", "dynamics"),
                                            ("bricard.yaml", "dynamics"),
                                            ("four_bar.yaml", "kinematics")])
def test_a_signal_between_rows_stops_at_the_next_row_with_the_rows(path, analysis):
    """The signal is raised from the row callback at row 20: outside a solver, so the
    interrupt waits for the next row; the rows before it come with the error."""
    functions = casmech.compile(casmech.load(MODELS / path))
    seen = []

    def on_row(t):
        seen.append(t)
        if len(seen) == 20:
            signal.raise_signal(signal.SIGINT)

    with interrupts.trap(), pytest.raises(Interrupted) as caught:
        casmech.analyze(functions, analysis, t_end=1.0, output_step=0.001,
                        progress=interrupts.watch(on_row))
    partial = caught.value.partial
    assert partial is not None and len(partial) >= 20
    assert partial.times[:20] == seen[:20]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # restored


def test_saving_waits_for_the_signal():
    with interrupts.trap():
        with interrupts.saving():
            signal.raise_signal(signal.SIGTERM)  # no raise while writing
        assert interrupts.pending() is not None
        with pytest.raises(Interrupted):
            interrupts.check()
    assert interrupts.pending() is None
