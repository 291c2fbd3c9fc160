"""Joint-coordinate dynamics of trees with method dop853 (runtime.dop853 through
runtime.joint_dynamics) against CVODES's Adams runs, a closed form, events, and the same steps
interpreted and compiled; where dop853 cannot run, a located error."""

import numpy as np
import pytest

import casmech
from casmech.backends import codegen
from casmech.errors import ModelError
from casmech.runtime.nonfinite import RatesNotFinite
from tests.conftest import MODELS
from tests.integration.runtime.test_nonfinite_rates import MODEL as NONFINITE
from tests.validation.runtime.test_dynamics import FREE_BODY, G, W
from tests.validation.runtime.test_events import PENDULUM, QUARTER, TIME, model

TREES = ("double_pendulum", "triple_pendulum", "flyball_governor", "cart_pole",
         "quadruped_legs")


@pytest.mark.parametrize("name", TREES)
def test_same_motion_as_adams(name):
    functions = casmech.compile(casmech.load(MODELS / f"{name}.yaml"), "interpreted")
    runs = {method: casmech.analyze(functions, "dynamics", t_end=0.5, output_step=0.05,
                                    rtol=1e-10, atol=1e-12, method=method)
            for method in ("adams", "dop853")}
    assert runs["dop853"].metadata["integrator"] == "dop853"
    assert 0 < runs["dop853"].metadata["steps"] < runs["adams"].metadata["steps"]
    for quantity in ("q", "q_dot"):
        adams, rk = (np.asarray(getattr(runs[m], quantity)) for m in ("adams", "dop853"))
        scale = max(1.0, np.abs(adams).max())
        # two integrators at rtol 1e-10 on the same ODE: global errors of ~1e-9 of the scale
        # (the joint-vs-rp comparison of test_joint_dynamics measured <= 4e-9)
        np.testing.assert_allclose(rk, adams, rtol=0, atol=1e-7 * scale, err_msg=quantity)


def test_pendulum_quarter_period_event():
    """The compound pendulum released from horizontal reaches the bottom at the complete
    elliptic integral's quarter period (tests/validation/runtime/test_events.py)."""
    functions = model(PENDULUM, '  - {name: bottom, when: "bar.x", direction: falling}\n')
    result = casmech.analyze(functions, formulation="joint", method="dop853")
    [event] = result.events
    assert abs(event.t - QUARTER) < TIME
    assert result.status == "complete" and result.times[-1] == 1.0


def test_compiled_takes_the_interpreted_steps(monkeypatch, tmp_path, quick_builds):
    """The C driver over the compiled ODE and scipy's stepper over the SX ODE: the same steps
    (the same algorithm) and states equal to roundoff."""
    if not codegen.available():
        pytest.skip("no C compiler")
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path))
    loaded = casmech.load(MODELS / "double_pendulum.yaml")
    runs = [casmech.analyze(casmech.compile(loaded, mode), "dynamics", t_end=1.0, rtol=1e-8,
                            atol=1e-10, method="dop853") for mode in ("interpreted", "compiled")]
    assert runs[0].metadata["steps"] == runs[1].metadata["steps"]
    # the same steps in another summation order (C's loops vs NumPy's dot) and the ODE's C
    # at -O0 vs CasADi's SX virtual machine: roundoff, grown over ~50 steps of a chaotic
    # double pendulum by far less than the integration error (1e-8)
    np.testing.assert_allclose(np.asarray(runs[1].q), np.asarray(runs[0].q), rtol=0,
                               atol=1e-11)


def test_free_flight_is_the_closed_form():
    """A free body (a `free` tree joint): parabola and steady spin."""
    functions = casmech.compile(casmech.loads(FREE_BODY), "interpreted")
    names, values = casmech.results_table(functions, casmech.analyze(
        functions, formulation="joint", method="dop853"))
    table = {name: values[:, k] for k, name in enumerate(names)}
    t = table["t"]
    start, velocity = np.array([0, 0, 1.0]), np.array([1.0, -0.5, 4.0])
    position = start[:, None] + np.outer(velocity, t) + 0.5 * np.outer(G, t**2)
    for k, axis in enumerate("xyz"):
        # rtol 1e-10 over 2 s; the translation is exactly quadratic, which an 8th-order
        # method integrates exactly but for roundoff
        np.testing.assert_allclose(table[f"box.{axis}"], position[k], rtol=0, atol=1e-10)
    # the spin: rtol 1e-10 over 2 s of a steady rotation
    np.testing.assert_allclose(table["box.e0"], np.cos(W * t / 2), rtol=0, atol=1e-8)
    np.testing.assert_allclose(table["box.e3"], np.sin(W * t / 2), rtol=0, atol=1e-8)


def test_loops_written_in_the_file_run_their_projected_ode():
    """method dop853 on a model with loops (the loops' projected ODE: formulations/loop_ode.py;
    its checks in tests/integration/runtime/test_loop_dop853.py), read from the file."""
    text = (MODELS / "four_bar_released.yaml").read_text().replace(
        "analysis:\n", "analysis:\n  method: dop853\n")
    functions = casmech.compile(casmech.loads(text, "four_bar.yaml"), "interpreted")
    metadata = casmech.analyze(functions, t_end=0.2).metadata
    assert (metadata["integrator"], metadata["method"]) == ("dop853", "dop853")
    assert metadata["cut_joints"] == ["rocker_pin"]


def test_rp_formulation_with_dop853_is_a_schema_error():
    text = (MODELS / "double_pendulum.yaml").read_text().replace(
        "analysis:\n", "analysis:\n  method: dop853\n  formulation: rp\n")
    with pytest.raises(ModelError, match=r"analysis\.method: method dop853 integrates joint"):
        casmech.loads(text, "double.yaml")


@pytest.mark.parametrize("mode", ["interpreted", "compiled"])
def test_rates_not_finite_name_the_interval(monkeypatch, tmp_path, quick_builds, mode):
    """A torque sqrt(angle + 0.3), undefined once the bar swings below -0.3 rad: the rows
    before are kept and the error names the output interval (runtime.nonfinite), as the CVODES
    run's does (tests/integration/runtime/test_nonfinite_rates.py)."""
    if mode == "compiled" and not codegen.available():
        pytest.skip("no C compiler")
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path))
    functions = casmech.compile(casmech.loads(NONFINITE % "sqrt(pivot.angle + 0.3)",
                                              "undefined_law.yaml"), mode)
    with pytest.raises(RatesNotFinite) as caught:
        casmech.analyze(functions, formulation="joint", method="dop853")
    error = caught.value
    table = casmech.results_table(functions, error.partial)
    angle = table[1][:, table[0].index("pivot.angle")]
    times = np.asarray(error.partial.times)
    assert len(times) > 5 and np.all(angle > -0.3) and error.t0 == times[-1]
    np.testing.assert_allclose(error.t1 - error.t0, 0.01, rtol=1e-9, atol=0)  # one interval
    assert "force 'bad'" in str(error)
