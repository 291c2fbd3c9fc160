"""`method: dop853` on mechanisms with loops: the loops' projected ODE (formulations/loop_ode.py,
runtime/projected_loops.py) through runtime.dop853, against the joint DAE on IDAS at tight
tolerance, the constraints at every results row, a conservative loop's energy from the results
table (numpy: tests/helpers/gallery_closed_forms.py), singular poses (IFToMM A02) and the
compiled path against the interpreted one."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import casmech
from casmech.errors import ModelError
from casmech.runtime import workspace
from tests.conftest import MODELS, ROOT, Table
from tests.helpers import gallery_closed_forms as cf
from tests.validation.runtime.test_events import TIME, parallelogram, swing_time
from tests.validation.runtime.test_events import model as event_model
from tests.validation.runtime.test_validation_iftomm import A02

LOOPS = ["four_bar_released", "bricard"]  # a planar loop; an overconstrained one (a row masked)


@pytest.fixture(scope="module", params=LOOPS)
def loop(request):
    model = casmech.load(MODELS / f"{request.param}.yaml")
    return model, casmech.compile(model)


def _run(functions, **settings):
    return casmech.analyze(functions, "dynamics", t_end=1.0, **settings)


def test_follows_the_dae_and_reports_its_multipliers(loop):
    _, functions = loop
    exact = _run(functions, rtol=1e-11, atol=1e-13, method="bdf")
    assert exact.metadata["integrator"] == "idas"
    result = _run(functions, rtol=1e-9, atol=1e-11, method="dop853")
    assert (result.metadata["integrator"], result.metadata["method"]) == ("dop853", "dop853")
    assert result.metadata["formulation"] == "joint" and result.metadata["singular_poses"] == []
    assert 0 < result.metadata["steps"] < exact.metadata["steps"]
    assert np.array_equal(result.times, exact.times)
    # rtol 1e-9 over 1 s of motion on coordinates ~1 (m, rad): the global error ~10 rtol;
    # IDAS at 1e-11 is exact to these digits
    np.testing.assert_allclose(result.q, exact.q, rtol=0, atol=1e-7)
    np.testing.assert_allclose(result.q_dot, exact.q_dot, rtol=0, atol=1e-6)
    # the multipliers solved at each row's state (N, N m ~10-100): their error follows the
    # states'
    scale = np.abs(exact.lam).max()
    np.testing.assert_allclose(result.lam, exact.lam, rtol=0, atol=1e-6 * scale)


def test_every_row_is_on_the_constraints(loop):
    """The output points are projected too: position and velocity constraints at roundoff at
    every row, where IDAS's rows carry its error (the rows of a loose run)."""
    _, functions = loop
    result = _run(functions, rtol=1e-4, atol=1e-6, method="dop853")
    for t, q, q_dot in zip(result.times, result.q, result.q_dot, strict=True):
        # |Phi| in m and rad (coordinates ~1): roundoff, 1e-12 with margin
        np.testing.assert_allclose(functions.vector("phi", t, q), 0, rtol=0, atol=1e-12)
        velocity = functions.matrix("phi_q", t, q) @ q_dot - functions.vector("nu", t, q)
        np.testing.assert_allclose(velocity, 0, rtol=0, atol=1e-11)


def test_a_conservative_loop_keeps_its_energy(loop):
    """Gravity and joints only: kinetic plus gravitational energy of the rows (numpy, from the
    table's columns) stays at its start's within the run's tolerance."""
    model, functions = loop
    result = _run(functions, rtol=1e-8, atol=1e-10, method="dop853")
    energy = cf.mechanical_energy(model, Table(*casmech.results_table(functions, result)))
    scale = max(1.0, abs(energy[0]))
    # rtol 1e-8 on coordinates ~1: the energy's error ~1e-8 of its scale, a few steps of it
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-7 * scale)


def test_singular_poses_are_reported_and_auto_runs_rp_after_them():
    """IFToMM A02 (N = 2) passes four flat poses by 3.5 s: the projected ODE steps over them
    as IDAS does, and the check after the run reports the same four (formulation joint), or
    (auto) runs the model again in rp."""
    functions = casmech.compile(casmech.load(A02))
    settings = dict(t_end=3.5, rtol=1e-7, atol=1e-9)
    idas = casmech.analyze(functions, "dynamics", formulation="joint", **settings)
    joint = casmech.analyze(functions, "dynamics", formulation="joint", method="dop853",
                            **settings)
    assert joint.metadata["integrator"] == "dop853"
    assert [p["t"] for p in joint.metadata["singular_poses"]] == \
        [p["t"] for p in idas.metadata["singular_poses"]]
    assert len(joint.metadata["singular_poses"]) == 4
    auto = casmech.analyze(functions, "dynamics", method="dop853", **settings)
    assert auto.metadata["formulation"] == "rp"
    assert auto.metadata["formulation_fallback"].startswith(
        "joint coordinates went near a singular pose at t = 0.71")


def _compiled_against_interpreted(model):
    """(bundles, runs): the model interpreted and compiled at rtol 1e-7 with dop853, the
    compiled run's steps in C and the interpreted one's in Python, the same steps and the
    same rows to roundoff (the callers' docstrings say why)."""
    bundles = [casmech.compile(model, mode) for mode in ("interpreted", "compiled")]
    runs = [_run(functions, rtol=1e-7, atol=1e-9, method="dop853") for functions in bundles]
    assert [[rk.compiled for rk in workspace.default(functions).store("dop853").values()]
            for functions in bundles] == [[False], [True]]
    assert runs[0].metadata["steps"] == runs[1].metadata["steps"]
    np.testing.assert_allclose(runs[1].q, runs[0].q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(runs[1].lam, runs[0].lam, rtol=0,
                               atol=1e-9 * np.abs(runs[0].lam).max())
    return bundles, runs


@pytest.mark.slow
def test_compiled_takes_the_interpreted_steps():
    """The compiled bundle's loop ODE and projection in C (runtime.dop853's C driver) against
    the interpreted ones on scipy's stepper: the same algorithm, so the same steps and the
    same rows to roundoff of the ODE's evaluation (its C and CasADi's virtual machine sum in
    other orders: ~1e-15 relative an evaluation, grown through ~20 steps of a motion that
    amplifies it; measured 2.3e-12 at most). The benchmark four-bar: a model
    without parameters, whose compiled bundle compiles the loop ODE."""
    model = casmech.load(ROOT / "benchmarks" / "models" / "four_bar.yaml")
    _compiled_against_interpreted(model)


def test_with_rp_it_is_a_located_error():
    """The r-p DAE of loops goes to IDAS: method dop853 with formulation rp is the schema's
    error at analysis.method."""
    text = (MODELS / "four_bar_released.yaml").read_text().replace(
        "analysis:\n", "analysis:\n  method: dop853\n  formulation: rp\n")
    with pytest.raises(ModelError) as raised:
        casmech.loads(text, "four_bar.yaml")
    [diagnostic] = raised.value.diagnostics
    assert diagnostic.path == "analysis.method" and diagnostic.source is not None
    assert diagnostic.got == "dop853" and "formulation: joint" in diagnostic.hint


def test_an_event_of_a_closed_loop_at_its_closed_form_time():
    """A parallelogram's crank angle crossing a value just after an output row: the event at
    the closed form's time (tests/validation/runtime/test_events.py's IDAS case, on the
    projected ODE: the trial steps of runtime.events through dop853)."""
    text, scale = parallelogram()
    crossing = 0.3 + 1e-9
    angle = brentq(lambda swung: swing_time(swung, math.pi / 4, scale) - crossing, 0.01,
                   math.pi / 4, xtol=1e-15)
    functions = event_model(text, f'  - {{name: at, when: "crank_pivot.angle - {angle!r}"}}\n')
    result = casmech.analyze(functions, formulation="joint", method="dop853")
    [event] = result.events
    assert result.metadata["integrator"] == "dop853" and result.metadata["cut_joints"]
    assert abs(event.t - crossing) < TIME


def test_a_controller_of_a_loop_reads_the_projected_run():
    """A Python controller's bundle holds forces its IR does not (runtime.joint_recorder: the
    loops' rows then from the algebraic states, here each row's consistent multipliers): the
    same PD on the four-bar's crank as a callback and written in the model."""
    text = (MODELS / "four_bar_released.yaml").read_text().replace(
        "    initial: {angle: 30 deg, angle_dot: 60 deg/s}\n",
        "    initial: {angle: 30 deg, angle_dot: 60 deg/s}\n    motor: {torque: LAW}\n")
    settings = {"t_end": 0.5, "rtol": 1e-10, "atol": 1e-12, "method": "dop853"}

    def bundle(law: str):
        return casmech.compile(casmech.loads(text.replace("LAW", law), "four_bar.yaml"))

    written = casmech.analyze(bundle("'-5 * angle - 0.5 * angle_dot'"), **settings)

    def law(t, state):
        return -5 * state["crank_pivot.angle"] - 0.5 * state["crank_pivot.angle_dot"]

    called = casmech.analyze(bundle("0"), controller=law, **settings)
    assert called.metadata["integrator"] == "dop853"
    # two rtol 1e-10 runs of one ODE (one through the controller's bound forces)
    np.testing.assert_allclose(called.q, written.q, rtol=0, atol=1e-7)
    # the multipliers: solved at each row (written) and the rows' consistent ones (called)
    np.testing.assert_allclose(called.lam, written.lam, rtol=0,
                               atol=1e-6 * np.abs(written.lam).max())


@pytest.mark.slow
def test_a_parametric_library_compiles_the_loops_once_per_structure():
    """A compiled gallery model with parameters: its loop ODE and projection compiled over the
    model data's symbols and bound to the bundle's data (runtime.projected_loops), in C, with
    the interpreted bundle's steps and rows to roundoff; another value of a parameter reuses
    the library (bound to its own data) and moves the motion."""
    model = casmech.load(MODELS / "four_bar_released.yaml")
    bundles, runs = _compiled_against_interpreted(model)
    assert bundles[1].joint_functions is not None and bundles[1].parametric is not None
    heavier = bundles[1].set(m=1.2)  # each link 1.2 kg instead of 0.8
    other = [_run(functions, rtol=1e-7, atol=1e-9, method="dop853")
             for functions in (heavier, casmech.compile(casmech.load(
                 MODELS / "four_bar_released.yaml", {"m": "1.2"}), "interpreted"))]
    assert [rk.compiled for rk in workspace.default(heavier).store("dop853").values()] == [True]
    np.testing.assert_allclose(other[0].q, other[1].q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(other[0].lam, other[1].lam, rtol=0,
                               atol=1e-9 * np.abs(other[1].lam).max())
    # the same motion (the masses scale together), reactions 1.5 times as large
    np.testing.assert_allclose(other[0].lam, 1.5 * runs[1].lam, rtol=0,
                               atol=1e-6 * np.abs(runs[1].lam).max())
