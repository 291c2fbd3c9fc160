"""What casmech.analyze keeps between calls and installs per call: checked settings kept by
the arguments that made them (a bad argument refused every time, 1 and 1.0 kept apart), and
the Ctrl-C handler installed once per call chain and restored after it."""

import signal

import pytest

import casmech
from casmech.errors import UsageError
from casmech.runtime import interrupts
from casmech.runtime.analyses import analysis_settings
from casmech.runtime.cancel import CancelToken
from tests.conftest import MODELS


@pytest.fixture(scope="module")
def functions():
    return casmech.compile(casmech.load(MODELS / "pendulum.yaml"))


def test_kept_settings_are_those_checked_afresh(functions):
    first = analysis_settings(functions, "dynamics", t_end=0.5, rtol=1e-7)
    again = analysis_settings(functions, "dynamics", t_end=0.5, rtol=1e-7)
    other = casmech.compile(casmech.load(MODELS / "pendulum.yaml"))  # a workspace of its own
    assert first is again and first == analysis_settings(other, "dynamics", t_end=0.5, rtol=1e-7)
    assert type(analysis_settings(functions, t_end=1).t_end) is int
    assert type(analysis_settings(functions, t_end=1.0).t_end) is float
    for _ in range(2):  # a refused argument is refused every time, never kept
        with pytest.raises(UsageError):
            analysis_settings(functions, rtol=-1.0)
    mapped = analysis_settings(functions, options={"max_step": 1e-3})  # not hashable
    assert mapped.options.solver.max_step == 1e-3
    assert analysis_settings(functions).options.solver.max_step is None


def test_the_handler_is_installed_for_the_call_and_restored(functions):
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    seen = []

    def on_row(t):
        seen.append(signal.getsignal(signal.SIGINT))

    casmech.analyze(functions, "dynamics", t_end=0.02, output_step=0.01, progress=on_row)
    assert seen and all(getattr(h, "__self__", None) is not None for h in seen)  # a _Trap's
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    with interrupts.guard(CancelToken()):
        outer = signal.getsignal(signal.SIGINT)
        with interrupts.guard(CancelToken()):  # nested: the outer handler serves both
            assert signal.getsignal(signal.SIGINT) is outer
        assert signal.getsignal(signal.SIGINT) is outer
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
