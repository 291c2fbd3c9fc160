"""A force law that turns non-finite along the motion (sqrt or log of a negative) stops a
dynamics run at once, in every integrator, with the interval, the element and the rows before
it (runtime.nonfinite.RatesNotFinite): the pendulum's torque sqrt(angle + 0.3) or
log(angle + 0.3) is undefined once the bar swings below angle -0.3 rad."""

import numpy as np
import pytest

import casmech
from casmech.errors import AnalysisError
from casmech.runtime.nonfinite import RatesNotFinite
from tests.conftest import count_calls

MODEL = """\
casmech: 1
name: undefined_law
bodies:
  - {name: bar, mass: 1, inertia: [0.01, 0.1, 0.1], position: [0.5, 0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 0, 1]}
forces:
  - {name: bad, type: torque, body: bar, value: [0, 0, "%s"]}
gravity: [0, -9.81, 0]
analysis: {type: dynamics, t_end: 2, output_step: 0.01}
"""
LAWS = {"sqrt": ("sqrt(pivot.angle + 0.3)", -0.3), "log": ("log(pivot.angle + 0.3)", -0.3)}
RUNS = {"joint": {"formulation": "joint"}, "rp": {"formulation": "rp"},
        "rp_fallback": {"formulation": "rp", "options": {"fallback.always": True}}}


@pytest.fixture(scope="module")
def compiled(tmp_path_factory):
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("CASMECH_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
        yield {name: casmech.compile(casmech.loads(MODEL % law, "undefined_law.yaml"))
               for name, (law, _) in LAWS.items()}


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("run", RUNS)
def test_a_law_that_turns_non_finite_fails_at_once(compiled, monkeypatch, tmp_path, law, run):
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path))
    functions, edge = compiled[law], LAWS[law][1]
    calls = count_calls(monkeypatch)
    with pytest.raises(AnalysisError) as caught:
        casmech.analyze(functions, **RUNS[run])
    error = caught.value
    assert isinstance(error, RatesNotFinite)
    # the rows before are kept, each where the law is defined; the interval named is the
    # output interval after the last of them, and the angle leaves the domain within it
    table = casmech.results_table(functions, error.partial)
    angle = table[1][:, table[0].index("pivot.angle")]
    rate = table[1][:, table[0].index("pivot.angle_dot")]
    times = np.asarray(error.partial.times)
    assert len(times) > 5 and np.all(angle > edge)
    assert error.t0 == times[-1]
    np.testing.assert_allclose(error.t1 - error.t0, 0.01, rtol=1e-9, atol=0)  # one interval
    assert angle[-1] + 0.01 * rate[-1] < edge + 0.01  # the edge is within reach of the last row
    text = str(error)
    assert text.startswith(f"analysis failed at t = {error.t0:.6g}: the equations of motion "
                           f"are not finite between t = {error.t0:.6g} and {error.t1:.6g}")
    assert "undefined_law.yaml:8:5: force 'bad'" in text
    # bounded work: the integrator stops at the first non-finite law (never tens of thousands
    # of ever shorter steps), and the driver narrows the chunk by halves
    integrators = sum(1 for name in calls if name in ("joint", "dynamics"))
    steps = sum(1 for name in calls if name.endswith("_rk4_step"))
    print(f"\n{run} {law}: {integrators} integrator calls, {steps} Runge-Kutta steps, "
          f"{len(calls)} Function calls")
    assert integrators <= (0 if run == "rp_fallback" else 2 * np.log2(len(times)) + 4)
    if run == "rp":
        assert steps == 0  # no fallback to Runge-Kutta: the DAE's failure is the law's
    else:  # a few tries of the failed interval, not the fallback's max_steps (50 000)
        assert steps <= (1000 if run == "rp_fallback" else 0)
