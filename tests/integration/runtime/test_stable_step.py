"""Method auto bounds DOP853's step by the stiffness probe's spectral radius
(runtime.stiffness.stable_step, runtime.joint_dynamics.run_joint_dynamics): on a tree whose
fastest mode is a damper's real decay (a light rod on a damped elbow, not stiff enough for BDF
at the output step), the bounded run rejects fewer steps than DOP853 named (scipy's steps,
unbounded), and both follow a tight BDF run; its outputs come from the Hermite pair without
evaluations on most output steps (runtime.dop853's free_outputs)."""

import numpy as np

import casmech
from casmech.runtime import dop853, joint_dynamics, workspace
from casmech.runtime.stiffness import STABLE_REAL, spectral_radius
from tests.conftest import MODELS
from tests.unit.runtime.test_dop853 import dense_steps

# the double pendulum with a light short second rod (0.05 kg, 0.2 m: 6.7e-4 kg m^2 about the
# elbow) on a 0.3 N m s/rad damper: a real eigenvalue near -0.3 / 6.7e-4 = -450 1/s, so
# 450 x 0.01 s = 4.5 < method auto's 10 (DOP853, not BDF) while DOP853's step, stable below
# 6.4 / 450 s, is held by that mode and not by the accuracy at loose tolerances
DAMPER = """
forces:
  - {name: elbow_damper, type: rsda, joint: elbow, stiffness: 0, free_angle: 0, damping: 0.3}
"""


def _model():
    text = (MODELS / "double_pendulum.yaml").read_text()
    text = text.replace("m2: 1.0 ", "m2: 0.05").replace("L2: 1.0 ", "L2: 0.2 ")
    return casmech.loads(text + DAMPER, file="<damped double pendulum>")


def _run(functions, **settings):
    return casmech.analyze(functions, "dynamics", **{"t_end": 1.0, **settings})


def _last_dop853(functions):
    return list(workspace.default(functions).store("dop853").values())[-1]


def test_auto_bounds_the_step_by_the_fastest_mode(quick_builds):
    model = _model()
    functions = casmech.compile(model, "compiled")
    exact = _run(casmech.compile(model, "interpreted"), method="bdf", rtol=1e-12, atol=1e-14)
    bounded = _run(functions, rtol=1e-4, atol=1e-6)
    assert bounded.metadata["method"] == "dop853"
    rk = _last_dop853(functions)
    kept = workspace.default(functions)
    system = joint_dynamics.joint_system(functions, joint_dynamics.DEFAULT, kept)
    x0 = joint_dynamics._start(functions, system, 0.0, joint_dynamics.DEFAULT.assembly, kept)[0]
    radius = spectral_radius(system, 0.0, x0)
    # the damper's decay rate: -c / (m2 L2^2 / 3) = -450 1/s less the first rod's share
    assert 300 < radius < 600
    np.testing.assert_allclose(rk.max_step, STABLE_REAL / radius, rtol=1e-12, atol=0)
    bounded_counts = rk.last
    named = _run(functions, rtol=1e-4, atol=1e-6, method="dop853")
    assert _last_dop853(functions).max_step == np.inf
    named_counts = _last_dop853(functions).last
    # the unbounded controller meets the stability boundary and swings about it
    assert named_counts.rejected >= 10
    assert bounded_counts.rejected < named_counts.rejected / 2
    assert bounded_counts.evaluations < named_counts.evaluations
    for run in (bounded, named):
        # rtol 1e-4, atol 1e-6 over 1 s: the angles (~1.6 rad) within a few hundred rtol
        np.testing.assert_allclose(run.q, exact.q, rtol=0, atol=5e-3)



def test_outputs_without_the_interpolants_evaluations(quick_builds, monkeypatch):
    model = _model()
    exact = _run(casmech.compile(model, "interpreted"), method="bdf", rtol=1e-12, atol=1e-14)
    runs, threshold = {}, dop853.HERMITE_BELOW
    for below in (threshold, 0.0):  # the Hermite pair, then DOP853's interpolant
        monkeypatch.setattr(dop853, "HERMITE_BELOW", below)
        functions = casmech.compile(model, "compiled")  # its own workspace: a new Dop853
        result = _run(functions, rtol=1e-3, atol=1e-5)
        rk = _last_dop853(functions)
        assert result.metadata["method"] == "dop853" and rk.free_outputs
        runs[below] = result, rk.last
    (free, free_stats), (dense, dense_stats) = runs[threshold], runs[0.0]
    output_steps = dense_steps(dense_stats)
    assert dense_stats.hermite == 0 and output_steps > 50
    # the same steps; most output steps interpolated by the Hermite pair, each 3 evaluations
    # fewer
    assert (free_stats.accepted, free_stats.rejected) == \
        (dense_stats.accepted, dense_stats.rejected)
    assert free_stats.hermite > 0.8 * output_steps
    assert dense_stats.evaluations - free_stats.evaluations == 3 * free_stats.hermite
    free_error = np.abs(free.q - exact.q).max()
    dense_error = np.abs(dense.q - exact.q).max()
    # rtol 1e-3 on angles of ~1.6 rad: within the tolerance, and within 2x DOP853's
    # interpolant's error (measured: no larger)
    assert free_error < 1e-3
    assert free_error <= 2 * dense_error
