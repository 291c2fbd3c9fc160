"""runtime.dop853: DOP853 over an output grid in C (backends/c/casmech_rk.c) and in Python
(runtime.dop853_steps), against scipy's solve_ivp, closed forms, and with a projection onto a
constraint."""

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import DOP853, solve_ivp

from casmech.backends import build
from casmech.backends.library import compile_functions
from casmech.runtime import dop853
from casmech.runtime.nonfinite import rates_failed

G = 9.81


def pendulum() -> tuple[ca.Function, ca.Function, ca.Function]:
    """A planar pendulum of unit length in Cartesian coordinates (px, py, vx, vy): its ODE (the
    rod force from the acceleration-level constraint), the projection onto the circle and its
    tangent, and its energy per unit mass."""
    t, x = ca.SX.sym("t"), ca.SX.sym("x", 4)
    p, v = x[:2], x[2:]
    lam = (ca.dot(v, v) - G * p[1]) / ca.dot(p, p)
    ode = ca.Function("pend_ode", [t, x], [ca.vertcat(v, -lam * p - ca.vertcat(0, G))],
                      ["t", "x"], ["ode"])
    unit = p / ca.norm_2(p)
    project = ca.Function("pend_project", [t, x],
                          [ca.vertcat(unit, v - ca.dot(v, unit) * unit)], ["t", "x"],
                          ["projected"])
    energy = ca.Function("energy", [x], [0.5 * ca.dot(v, v) + G * p[1]])
    return ode, project, energy


@pytest.fixture(scope="module")
def compiled_pendulum(tmp_path_factory):
    if not build.available(build.Toolchain()):
        pytest.skip("no C compiler")
    ode, project, _ = pendulum()
    return compile_functions({"pend_ode": ode, "pend_project": project},
                             root=tmp_path_factory.mktemp("cache"))


X0 = np.array([1.0, 0.0, 0.0, 0.5])
TIMES = np.linspace(0.1, 5.0, 50)


def scipy_steps(ode: ca.Function, rtol: float) -> int:
    """The steps scipy's DOP853 takes from X0 over TIMES."""
    solver = DOP853(lambda t, y: np.asarray(ode(t, y)).ravel(), 0.0, X0, TIMES[-1],
                    rtol=rtol, atol=rtol / 100)
    steps = 0
    while solver.status == "running":
        solver.step()
        steps += 1
    return steps


@pytest.mark.parametrize("rtol", [1e-5, 1e-9])
def test_c_takes_scipys_steps(compiled_pendulum, rtol):
    ode = pendulum()[0]
    reference = solve_ivp(lambda t, y: np.asarray(ode(t, y)).ravel(), (0.0, TIMES[-1]), X0,
                          "DOP853", t_eval=TIMES, rtol=rtol, atol=rtol / 100)
    rk = dop853.Dop853(compiled_pendulum["pend_ode"], rtol, rtol / 100)
    assert rk.compiled
    states = rk(0.0, TIMES, X0)
    assert rk.last.evaluations == reference.nfev
    assert rk.last.accepted == scipy_steps(ode, rtol)
    # the same arithmetic in another summation order: roundoff (1e-16 a step) grown over the
    # run's steps by the pendulum's divergence stays far below the integration error (>=1e-9)
    np.testing.assert_allclose(states, reference.y, rtol=1e-10, atol=1e-11)


@pytest.mark.parametrize("rtol", [1e-5, 1e-9])
def test_python_path_takes_scipys_steps(rtol):
    ode = pendulum()[0]
    reference = solve_ivp(lambda t, y: np.asarray(ode(t, y)).ravel(), (0.0, TIMES[-1]), X0,
                          "DOP853", t_eval=TIMES, rtol=rtol, atol=rtol / 100)
    rk = dop853.Dop853(ode, rtol, rtol / 100)
    assert not rk.compiled  # an SX function: no C entry point
    states = rk(0.0, TIMES, X0)
    assert rk.last.evaluations == reference.nfev
    assert rk.last.accepted == scipy_steps(ode, rtol)
    # the step's stages summed inside CasADi instead of by NumPy's dot: roundoff, as for C
    np.testing.assert_allclose(states, reference.y, rtol=1e-10, atol=1e-11)


def test_harmonic_oscillator_closed_form():
    t, x = ca.SX.sym("t"), ca.SX.sym("x", 2)
    omega = 3.0
    ode = ca.Function("oscillator", [t, x], [ca.vertcat(x[1], -omega**2 * x[0])], ["t", "x"],
                      ["ode"])
    states = dop853.Dop853(ode, 1e-10, 1e-12)(0.0, TIMES, [1.0, 0.0])
    exact = np.vstack([np.cos(omega * TIMES), -omega * np.sin(omega * TIMES)])
    # rtol 1e-10 per step over ~100 steps of an oscillation of amplitude 3
    np.testing.assert_allclose(states, exact, rtol=0, atol=1e-8)


@pytest.mark.parametrize("use_c", [True, False])
def test_projection_holds_the_constraint(compiled_pendulum, use_c):
    ode, project, energy = pendulum()
    functions = (compiled_pendulum["pend_ode"], compiled_pendulum["pend_project"]) if use_c \
        else (ode, project)
    free = dop853.Dop853(functions[0], 1e-6, 1e-8, use_c=use_c)
    projected = dop853.Dop853(functions[0], 1e-6, 1e-8, project=functions[1], use_c=use_c)
    assert projected.compiled == use_c
    plain, held = free(0.0, TIMES, X0), projected(0.0, TIMES, X0)
    drift = np.abs(np.hypot(plain[0], plain[1]) - 1).max()
    assert drift > 1e-7  # the unprojected run leaves the circle
    # the projected outputs lie on the circle to roundoff, their velocities tangent
    np.testing.assert_allclose(np.hypot(held[0], held[1]), 1.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.sum(held[:2] * held[2:], axis=0), 0.0, rtol=0, atol=1e-14)
    e0 = float(energy(X0))
    energies = np.array([float(energy(held[:, j])) for j in range(len(TIMES))])
    plain_energies = np.array([float(energy(plain[:, j])) for j in range(len(TIMES))])
    # the projection keeps the energy within the integration error, as the free run does
    np.testing.assert_allclose(energies, e0, rtol=0, atol=1e-4)
    assert np.abs(plain_energies - e0).max() > 1e-7
    assert projected.last.projections == projected.last.accepted + len(TIMES)


def test_c_projection_matches_python(compiled_pendulum):
    ode, project, _ = pendulum()
    c = dop853.Dop853(compiled_pendulum["pend_ode"], 1e-8, 1e-10,
                      project=compiled_pendulum["pend_project"])
    python = dop853.Dop853(ode, 1e-8, 1e-10, project=project)
    # the same steps in C and in Python: roundoff apart (as above)
    np.testing.assert_allclose(c(0.0, TIMES, X0), python(0.0, TIMES, X0), rtol=1e-10,
                               atol=1e-11)
    assert c.last.evaluations == python.last.evaluations


def singular() -> ca.Function:
    """x' = 1 / (1 - t): not finite at t = 1."""
    t, x = ca.SX.sym("t"), ca.SX.sym("x")
    return ca.Function("blowup", [t, x], [1 / (1 - t) + 0 * x], ["t", "x"], ["ode"])


@pytest.mark.parametrize("use_c", [True, False])
def test_failures(tmp_path, use_c):
    if use_c and not build.available(build.Toolchain()):
        pytest.skip("no C compiler")
    ode = singular()
    if use_c:
        ode = compile_functions({"blowup": ode}, root=tmp_path)["blowup"]
    times = np.linspace(0.25, 2.0, 8)
    with pytest.raises(dop853.Failure) as failed:
        dop853.Dop853(ode, 1e-6, 1e-8, use_c=use_c)(0.0, times, [0.0])
    # the rows before the singularity are kept, as -log(1 - t)
    outputs = failed.value.outputs
    assert 0 < outputs.shape[1] < 4
    np.testing.assert_allclose(outputs[0], -np.log(1 - times[:outputs.shape[1]]), rtol=1e-5,
                               atol=1e-8)  # rtol 1e-6 per step near a pole
    message = str(failed.value)
    assert rates_failed(failed.value) or dop853.TOO_SMALL in message
    with pytest.raises(dop853.Failure, match="more than 3 steps before the next output"):
        dop853.Dop853(ode, 1e-10, 1e-12, max_steps=3, use_c=use_c)(0.0, [0.5], [0.0])


def test_times_at_the_start_are_the_start():
    ode = pendulum()[0]
    rk = dop853.Dop853(ode, 1e-8, 1e-10)
    states = rk(0.5, [0.5, 0.5, 1.0], X0)
    np.testing.assert_array_equal(states[:, :2], np.column_stack([X0, X0]))
    # the rest as a call from the start over the later times alone (the same steps)
    np.testing.assert_array_equal(states[:, 2], rk(0.5, [1.0], X0)[:, 0])
    np.testing.assert_array_equal(rk(0.5, [0.5], X0)[:, 0], X0)


def test_c_calls_reusing_their_arrays_are_independent(compiled_pendulum, monkeypatch):
    """One instance called over grids of several lengths (longer, shorter, and past the
    length whose arrays it keeps) from several starts gives what a new instance gives, and a
    call's states are not changed by the calls after it (the kept output array is copied)."""
    monkeypatch.setattr(dop853, "BOUND_ENTRIES", 4 * 60)  # the pendulum's 4 states, 60 times
    ode = compiled_pendulum["pend_ode"]
    kept = dop853.Dop853(ode, 1e-8, 1e-10)
    grids = [TIMES[:10], TIMES, np.linspace(0.05, 6.0, 80), TIMES[:3], TIMES]
    starts = [X0, X0 * [1, 1, 1, -1], X0, X0 * [1, 1, 1, 2], X0]
    first = None
    for times, x0 in zip(grids, starts, strict=True):
        got = kept(0.0, times, x0)
        fresh = dop853.Dop853(ode, 1e-8, 1e-10)(0.0, times, x0)
        assert fresh.shape == got.shape
        np.testing.assert_array_equal(got, fresh)  # the same C on the same numbers
        if first is None:
            first, first_copy = got, got.copy()
    np.testing.assert_array_equal(first, first_copy)


# free_outputs: a slow oscillation p'' = -p followed by w with a fast real decay (rate FAST,
# a step bounded at 6.2 / FAST as method auto bounds it: runtime.stiffness.stable_step)
FAST = 400.0


def fast_mode() -> ca.Function:
    t, x = ca.SX.sym("t"), ca.SX.sym("x", 3)
    return ca.Function("fast_ode", [t, x], [ca.vertcat(x[1], -x[0], -FAST * (x[2] - x[0]))],
                       ["t", "x"], ["ode"])


def fast_mode_exact(times: np.ndarray, w0: float) -> np.ndarray:
    """The closed form from (1, 0, w0) at t = 0: w the forced decay towards p = cos t."""
    def forced(s):
        return FAST * (FAST * np.cos(s) + np.sin(s)) / (FAST**2 + 1)

    return np.vstack([np.cos(times), -np.sin(times),
                      forced(times) + (w0 - forced(0.0)) * np.exp(-FAST * times)])


@pytest.fixture(scope="module")
def compiled_fast(tmp_path_factory):
    if not build.available(build.Toolchain()):
        pytest.skip("no C compiler")
    return compile_functions({"fast_ode": fast_mode()},
                             root=tmp_path_factory.mktemp("cache"))["fast_ode"]


def dense_steps(stats: dop853.Stats) -> int:
    """The output steps that evaluated DOP853's interpolant: a call's evaluations less the
    first derivative, the initial step's and 12 a step attempt, 3 each."""
    attempts = stats.accepted + stats.rejected
    return (stats.evaluations - 2 - dop853.T_STAGES * attempts) // dop853.T_EXTRA


@pytest.mark.parametrize("rtol", [1e-3, 1e-7])
def test_free_outputs_where_the_step_is_stability_bounded(compiled_fast, rtol):
    bound, x0 = 6.2 / FAST, [1.0, 0.0, 1.0]
    exact = fast_mode_exact(TIMES, x0[2])
    runs = {}
    for free in (False, True):
        for use_c in (True, False):
            rk = dop853.Dop853(compiled_fast if use_c else fast_mode(), rtol, rtol / 100,
                               max_step=bound, free_outputs=free, use_c=use_c)
            assert rk.compiled == use_c
            runs[free, use_c] = rk(0.0, TIMES, x0), rk.last
    for use_c in (True, False):
        (dense, dense_stats), (free, free_stats) = runs[False, use_c], runs[True, use_c]
        assert dense_stats.hermite == 0 and dense_steps(dense_stats) == len(TIMES)
        # the same steps; every output step after the first (none here: TIMES start at 0.1)
        # interpolated without evaluations
        assert (free_stats.accepted, free_stats.rejected) == \
            (dense_stats.accepted, dense_stats.rejected)
        assert free_stats.hermite == len(TIMES) and dense_steps(free_stats) == 0
        assert free_stats.evaluations == dense_stats.evaluations - 3 * len(TIMES)
        dense_error = np.abs(dense - exact).max()
        free_error = np.abs(free - exact).max()
        # within the tolerance of the closed form (O(1) states), and no worse than DOP853's
        # interpolant, which magnifies the fast mode inside a step at h lambda = -6.2
        assert free_error < rtol
        assert free_error <= dense_error
    # C and Python: the same decisions, the outputs roundoff apart (as above)
    assert runs[True, True][1] == runs[True, False][1]
    np.testing.assert_allclose(runs[True, True][0], runs[True, False][0], rtol=1e-10,
                               atol=1e-11)


@pytest.mark.parametrize("use_c", [True, False])
def test_the_estimate_refuses_a_fast_transient(compiled_fast, use_c):
    ode = compiled_fast if use_c else fast_mode()
    x0 = [1.0, 0.0, 5.0]  # w starts 4 away from its slow manifold w ~ p: a transient of e^-400t
    calls = {}
    for times in (np.linspace(0.01, 1.0, 100), np.linspace(0.2, 1.0, 81)):
        rk = dop853.Dop853(ode, 1e-5, 1e-7, max_step=6.2 / FAST, free_outputs=True,
                           use_c=use_c)
        states = rk(0.0, times, x0)
        # the outputs within the tolerance of the closed form (O(1) states, rtol 1e-5)
        np.testing.assert_allclose(states, fast_mode_exact(times, x0[2]), rtol=0, atol=1e-4)
        calls[len(times)] = rk.last
    # outputs from the start: the first step has no step before it, and the estimate refuses
    # the next ones, inside the transient (DOP853's interpolant); after it (from 0.2 s), none
    assert dense_steps(calls[100]) >= 3
    assert dense_steps(calls[81]) == 0 and calls[81].hermite > 0


@pytest.mark.parametrize("use_c", [True, False])
def test_the_estimate_refuses_accuracy_limited_steps(compiled_pendulum, use_c):
    ode = compiled_pendulum["pend_ode"] if use_c else pendulum()[0]
    plain = dop853.Dop853(ode, 1e-5, 1e-7, use_c=use_c)
    free = dop853.Dop853(ode, 1e-5, 1e-7, free_outputs=True, use_c=use_c)
    # steps as long as the 8th-order accuracy allows (no bound): the cubic's error, which the
    # estimate measures, is far above the tolerance, so every output comes from DOP853's
    # interpolant, as without free_outputs
    np.testing.assert_array_equal(free(0.0, TIMES, X0), plain(0.0, TIMES, X0))
    assert free.last == plain.last and free.last.hermite == 0


def test_free_outputs_are_off_by_default_and_with_a_projection(compiled_pendulum):
    ode, project = compiled_pendulum["pend_ode"], compiled_pendulum["pend_project"]
    assert not dop853.Dop853(ode, 1e-6, 1e-8).free_outputs
    assert dop853.from_options(ode, {"reltol": 1e-6, "abstol": 1e-8}).hermite_below == 0
    assert dop853.from_options(ode, {"reltol": 1e-6, "abstol": 1e-8,
                                     dop853.FREE_OUTPUTS: True}).hermite_below > 0
    projected = dop853.Dop853(ode, 1e-6, 1e-8, project=project, max_step=0.01,
                              free_outputs=True)
    assert projected.hermite_below == 0
    projected(0.0, TIMES, X0)
    assert projected.last.hermite == 0
