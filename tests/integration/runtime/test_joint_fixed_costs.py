"""What a joint-coordinate run keeps in the bundle's workspace besides its integrators (method
auto's stiffness probe): a later run with other options takes the decision a fresh bundle
takes and gives its rows; a repeated run evaluates no Jacobian (call counts and equalities,
never timings)."""

import numpy as np

import casmech
from tests.conftest import count_calls
from tests.validation.runtime.test_joint_dynamics import STIFF_ARM


def _run(functions, t_end=0.05, **options):
    return casmech.analyze(functions, "dynamics", t_end=t_end, **options)


def test_method_auto_probes_stiffness_once_per_start_and_decides_per_run(monkeypatch):
    stiff = casmech.compile(casmech.loads(STIFF_ARM))
    first = _run(stiff)
    assert first.metadata["method"] == "bdf"
    calls = count_calls(monkeypatch)
    again = _run(stiff)
    assert again.metadata["method"] == "bdf"
    assert not any(name.startswith(("jac", "map_fwd")) for name in calls), calls
    np.testing.assert_array_equal(again.q, first.q)  # the same computation, repeated
    # the kept radius (~2.6e4 1/s) is judged against each run's threshold and output step:
    # another threshold or a fine enough grid makes it explicit (Adams on this interpreted
    # bundle: runtime.joint_dynamics.choose_method), as on a fresh bundle (short runs: an
    # explicit method on this stiff tip takes many steps)
    for options in ({"options": {"solver.stiff_threshold": 1e12}}, {"output_step": 1e-4}):
        kept = _run(stiff, 0.005, **options)
        fresh = _run(casmech.compile(casmech.loads(STIFF_ARM)), 0.005, **options)
        assert kept.metadata["method"] == fresh.metadata["method"] == "adams", options
        np.testing.assert_array_equal(kept.q, fresh.q)
    assert _run(stiff).metadata["method"] == "bdf"


def test_the_kept_radius_is_per_start():
    """Another t0 starts from another state: its radius is probed and kept beside the first,
    and its run equals a fresh bundle's."""
    from casmech.runtime.joint_dynamics import run_joint_dynamics
    from casmech.runtime.workspace import default

    stiff = casmech.compile(casmech.loads(STIFF_ARM))
    _run(stiff)
    later = run_joint_dynamics(stiff, 0.15, 0.01, 1e-6, 1e-8, t0=0.1, method="auto")
    assert len(default(stiff).store("stiffness")) == 2
    fresh = run_joint_dynamics(casmech.compile(casmech.loads(STIFF_ARM)), 0.15, 0.01, 1e-6,
                               1e-8, t0=0.1, method="auto")
    assert later.metadata["method"] == fresh.metadata["method"] == "bdf"
    np.testing.assert_array_equal(later.q, fresh.q)


def test_the_row_at_t0_is_kept_with_the_start_per_loop_rows_choice(monkeypatch):
    """The results rows at t0 are a function of the kept start and of whether the loops'
    rows are solved: a repeated run evaluates only its block's rows, each choice its own first
    row, and the rows equal a fresh bundle's; a run of that row alone hands out its own
    arrays (writing into them leaves the next run's as they were)."""
    from casmech.runtime import joint_recorder
    from casmech.runtime.joint_dynamics import run_joint_dynamics
    from tests.validation.runtime.test_joint_dynamics import ROOT

    path = ROOT / "benchmarks" / "models" / "four_bar.yaml"
    functions = casmech.compile(casmech.load(path))
    for loop_rows in ("solved", "integrator"):
        _run(functions, options={"solver.loop_rows": loop_rows})
    evaluated, rows = [], joint_recorder.Recorder.rows
    monkeypatch.setattr(joint_recorder.Recorder, "rows", lambda self, times, *args: (
        evaluated.append(len(times)) or rows(self, times, *args)))
    for loop_rows in ("solved", "integrator"):
        options = {"options": {"solver.loop_rows": loop_rows}}
        again = _run(functions, **options)
        fresh = _run(casmech.compile(casmech.load(path)), **options)
        for name in ("q", "q_dot", "q_ddot", "lam"):
            # the same computation, repeated
            np.testing.assert_array_equal(getattr(again, name), getattr(fresh, name))
    # a block of rows per kept run; the fresh bundles' first rows too
    assert evaluated == [5, 1, 5] * 2, evaluated
    only = run_joint_dynamics(functions, 0.0, 0.01, 1e-6, 1e-8)  # the row at t0 alone
    kept = only.lam.copy()
    only.lam[:] += 1.0
    # the kept row, untouched by the write
    np.testing.assert_array_equal(run_joint_dynamics(functions, 0.0, 0.01, 1e-6, 1e-8).lam,
                                  kept)


def test_a_kept_integrators_steps_are_read_once_per_inputs(monkeypatch):
    """A repeated run from the same start calls its kept integrator with the same inputs: the
    steps of the first run's call are reported again, its statistics read once; a run from
    another start (t0) reads them for its own call, and every count is a fresh bundle's."""
    from casmech.runtime import buffers
    from casmech.runtime.joint_dynamics import run_joint_dynamics

    def runs(functions):
        return [run_joint_dynamics(functions, t_end, 0.01, 1e-6, 1e-8, t0=t0)
                for t0, t_end in ((0.0, 0.1), (0.0, 0.1), (0.05, 0.1), (0.0, 0.1))]

    fresh = [r.metadata["steps"] for r in runs(casmech.compile(casmech.loads(STIFF_ARM)))]
    read, stats = [], buffers.NamedCall.stats
    monkeypatch.setattr(buffers.NamedCall, "stats", lambda self: read.append(1) or stats(self))
    kept = [r.metadata["steps"] for r in runs(casmech.compile(casmech.loads(STIFF_ARM)))]
    assert kept == fresh and fresh[0] > 0, (kept, fresh)
    assert len(read) == 2  # the first start's call, the other start's (its own grid)


def test_steps_are_read_again_for_other_inputs():
    """The kept count is of the inputs it was read for: other inputs read the statistics
    of their own call."""
    import casadi as ca

    from casmech.runtime.buffers import NamedCall
    from casmech.runtime.joint_dynamics import _steps

    x = ca.SX.sym("x", 2)
    integrator = NamedCall(ca.integrator("i", "cvodes", {"x": x, "ode": ca.vertcat(
        x[1], -x[0] * (1 + x[0] ** 2))}, 0.0, [1.0, 2.0], {"reltol": 1e-8}))
    counts = []
    for start in ([0.1, 0.0], [0.1, 0.0], [3.0, 0.0]):
        integrator(x0=np.array(start))
        counts.append((_steps(integrator, start), integrator.stats()["nsteps"]))
    assert counts[0] == counts[1] and counts[2][0] == counts[2][1] != counts[0][0], counts


def test_a_repeated_loop_run_finds_what_its_start_derived_without_the_workspace(monkeypatch):
    """The Recorder, the loops' projected ODE and DOP853 of a run are found again in its kept
    start's entries: a repeated run of the four-bar looks none of them up in the workspace
    (whose keys hash CasADi Functions), and its rows equal a fresh bundle's."""
    from casmech.runtime.workspace import Workspace
    from tests.validation.runtime.test_joint_dynamics import ROOT

    path = ROOT / "benchmarks" / "models" / "four_bar.yaml"
    functions = casmech.compile(casmech.load(path))
    first = _run(functions, method="dop853")
    asked, kept = [], Workspace.kept
    monkeypatch.setattr(Workspace, "kept", lambda self, kind, key, build: (
        asked.append(kind) or kept(self, kind, key, build)))
    again = _run(functions, method="dop853")
    assert again.metadata["method"] == "dop853"
    found = {"joint_least_norm", "joint_loop_rows", "loop_ode", "dop853"} & set(asked)
    assert not found, asked
    monkeypatch.undo()
    fresh = _run(casmech.compile(casmech.load(path)), method="dop853")
    for name in ("q", "q_dot", "q_ddot", "lam"):
        # the same computation, repeated
        np.testing.assert_array_equal(getattr(again, name), getattr(fresh, name))
        np.testing.assert_array_equal(getattr(again, name), getattr(first, name))
    assert again.metadata["tree"] == fresh.metadata["tree"]
    again.metadata["tree"].append("x")  # each run's own list
    assert _run(functions, method="dop853").metadata["tree"] == fresh.metadata["tree"]
