"""Method auto's explicit method follows where DOP853 would run (runtime.joint_dynamics
.choose_method, runtime.dop853.in_c): on a compiled bundle its steps run in C and it is
DOP853; on an interpreted bundle, or without the C driver, it is CVODES's Adams, whose fewer
evaluations a step cost less in CasADi's virtual machine. Either way the motion is the
model's: both against a run at tight tolerance. (Loops: a compiled bundle's projected ODE on
DOP853, tests/integration/backends/test_parametric.py; interpreted, IDAS,
tests/validation/runtime/test_events.py.)"""

import numpy as np

import casmech
from casmech.backends import rk_library
from tests.conftest import MODELS


def _run(functions, **settings):
    return casmech.analyze(functions, "dynamics", **{
        "t_end": 1.0, "rtol": 1e-8, "atol": 1e-10, **settings})


def test_the_explicit_method_follows_the_backend(quick_builds, monkeypatch):
    model = casmech.load(MODELS / "double_pendulum.yaml")
    interpreted, compiled = (casmech.compile(model, mode) for mode in ("interpreted",
                                                                       "compiled"))
    runs = [_run(functions) for functions in (interpreted, compiled)]
    assert [run.metadata["method"] for run in runs] == ["adams", "dop853"]
    exact = _run(interpreted, method="bdf", rtol=1e-12, atol=1e-14)
    for run in runs:
        # rtol 1e-8 over 1 s of the double pendulum (angles ~1 rad): either method's global
        # error is a few hundred rtol at most (BDF at 1e-12 the exact to these digits)
        np.testing.assert_allclose(run.q, exact.q, rtol=0, atol=1e-5)
    # no C driver (no compiler for it, or its build failed): DOP853 would take its Python
    # path, so auto takes Adams (a new bundle: the answer is kept per bundle); dop853 asked
    # still runs
    monkeypatch.setitem(rk_library._loaded, "run", None)
    again = casmech.compile(model, "compiled")
    assert _run(again).metadata["method"] == "adams"
    assert _run(again, method="dop853").metadata["method"] == "dop853"


def test_a_bundle_without_parameters_runs_its_steps_in_c(quick_builds):
    """A model without parameters compiles its values into its library (no bound model data):
    its joint ODE is the external backends.load recorded, reached in C (backends.rk_library),
    and auto takes DOP853."""
    from casmech.runtime import workspace
    from tests.conftest import ROOT

    model = casmech.load(ROOT / "benchmarks" / "models" / "chain2.yaml")
    assert not model.parameters
    functions = casmech.compile(model, "compiled")
    assert functions.parametric is None
    assert _run(functions, t_end=0.2).metadata["method"] == "dop853"
    assert [rk.compiled for rk in workspace.default(functions).store("dop853").values()] == [True]
