"""A repeated analysis's plan (runtime.analyses' plan, runtime.joint_run.JointRun): what
`analyze` derives from its arguments is kept in the run's workspace and reused only for the
same arguments on the same bundle. Every other call (another t_end, output step, tolerance,
method, formulation, options, parameter values) gets the rows a fresh workspace gives, and a
Result returned earlier is never changed by a later run. Equalities and counts, never timings."""

import numpy as np
import pytest

import casmech
from casmech.core.options import DynamicsOptions, DynamicsSolver
from casmech.runtime import formulation_run
from casmech.runtime import workspace as workspaces
from casmech.runtime.workspace import Workspace
from tests.conftest import MODELS, ROOT

BASE = {"t_end": 0.3, "rtol": 1e-6, "atol": 1e-8}
STATES = ("t", "q", "q_dot", "q_ddot", "lam")


@pytest.fixture(scope="module")
def functions():
    return casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"), "interpreted")


@pytest.fixture
def prepared(monkeypatch) -> list:
    """Every run of joint coordinates prepared from now on (runtime.joint_dynamics.prepare,
    as formulation_run calls it)."""
    made, original = [], formulation_run.prepare

    def prepare(*args, **kwargs):
        made.append(args[1:5])
        return original(*args, **kwargs)

    monkeypatch.setattr(formulation_run, "prepare", prepare)
    return made


def _fresh(functions, **settings):
    """The run in a workspace of its own: nothing kept from earlier runs."""
    return casmech.analyze(functions, workspace=Workspace(functions), **settings)


def _same(result, expected) -> None:
    for name in STATES:
        np.testing.assert_array_equal(getattr(result, name), getattr(expected, name),
                                      err_msg=name)
    assert result.metadata == expected.metadata


def _differ(result, other) -> bool:
    return any(np.shape(getattr(result, name)) != np.shape(getattr(other, name))
               or not np.array_equal(getattr(result, name), getattr(other, name))
               for name in STATES)


def test_a_repeated_analysis_is_prepared_once_and_gives_a_fresh_runs_rows(functions, prepared):
    first = casmech.analyze(functions, **BASE)
    count = len(prepared)
    again = [casmech.analyze(functions, **BASE) for _ in range(3)]
    assert count == 1 and len(prepared) == count  # the plan's prepared run, three times
    fresh = _fresh(functions, **BASE)  # prepared again in its own workspace
    assert len(prepared) == count + 1
    for result in (*again, fresh):
        _same(result, first)
    assert first.metadata["formulation"] == "joint" and len(first.t) == 31


# each: the arguments besides BASE's that make another analysis (another plan)
CHANGES = {
    "t_end": {"t_end": 0.2},
    "output_step": {"output_step": 0.02},
    "rtol": {"rtol": 1e-9, "atol": 1e-11},
    "method": {"method": "bdf"},
    "formulation": {"formulation": "rp"},
    "options": {"options": DynamicsOptions(solver=DynamicsSolver(joint_chunk=7))},
    "options mapping": {"options": {"max_step": 1e-3}},
    "analysis": {"analysis": "assembly"},
}


@pytest.mark.parametrize("change", CHANGES)
def test_another_analysis_on_the_same_bundle_is_not_given_the_kept_plan(functions, change):
    """Between runs of BASE, a run with `change`: each gives a fresh workspace's rows (and the
    changed run differs from BASE's, so a kept plan given to it would show)."""
    base = casmech.analyze(functions, **BASE)
    changed = casmech.analyze(functions, **(BASE | CHANGES[change]))
    _same(changed, _fresh(functions, **(BASE | CHANGES[change])))
    assert _differ(changed, base)
    _same(casmech.analyze(functions, **BASE), base)
    _same(casmech.analyze(functions, **(BASE | CHANGES[change])), changed)


def test_other_parameter_values_start_elsewhere(functions):
    """`set` makes another bundle: its run starts from its own initial state."""
    base = casmech.analyze(functions, **BASE)
    moved = functions.set(theta1=1.0)
    result = casmech.analyze(moved, **BASE)
    assert not np.array_equal(result.q[0], base.q[0])
    _same(result, _fresh(casmech.compile(casmech.load(MODELS / "double_pendulum.yaml",
                                                      overrides={"theta1": "1.0"}),
                                         "interpreted"), **BASE))
    _same(casmech.analyze(functions, **BASE), base)


def test_a_result_returned_earlier_is_not_changed_by_later_runs(functions):
    first = casmech.analyze(functions, **BASE)
    kept = {name: np.array(getattr(first, name), copy=True) for name in STATES}
    metadata = {key: (list(value) if isinstance(value, list) else value)
                for key, value in first.metadata.items()}
    second = casmech.analyze(functions, **BASE)
    for name in STATES:  # no array shared with a later run's
        assert not np.shares_memory(getattr(first, name), getattr(second, name)), name
    second.q[:] = np.nan  # a caller writing into its own Result
    second.metadata["tree"].append("not a joint")
    second.metadata["rtol"] = 0.5
    third = casmech.analyze(functions, **BASE)
    for name in STATES:
        np.testing.assert_array_equal(getattr(first, name), kept[name], err_msg=name)
        np.testing.assert_array_equal(getattr(third, name), kept[name], err_msg=name)
    assert first.metadata == metadata and third.metadata == metadata


def test_each_run_reports_to_its_own_progress(functions):
    seen: dict[str, list[float]] = {"one": [], "two": []}
    casmech.analyze(functions, **BASE, progress=seen["one"].append)
    count = len(seen["one"])
    casmech.analyze(functions, **BASE, progress=seen["two"].append)
    casmech.analyze(functions, **BASE)
    assert count == 31 and seen["two"] == seen["one"]


def test_dropping_any_kind_of_entry_drops_the_plans(functions, prepared):
    own = Workspace(functions)
    casmech.analyze(functions, **BASE, workspace=own)
    casmech.analyze(functions, **BASE, workspace=own)
    assert len(prepared) == 1 and len(own.store("analysis_plans")) == 1
    own.drop("joint_starts")
    assert len(own.store("analysis_plans")) == 0
    casmech.analyze(functions, **BASE, workspace=own)
    assert len(prepared) == 2
    # the default workspace's plans are its own
    assert own.store("analysis_plans") is not workspaces.default(functions).store(
        "analysis_plans")


def test_a_compiled_loop_repeated_gives_a_fresh_runs_rows(quick_builds):
    """The four-bar compiled (its loop's projected ODE by DOP853 in C, its singular poses
    examined after every run): repeated runs and a fresh workspace's, bit for bit."""
    functions = casmech.compile(casmech.load(ROOT / "benchmarks" / "models" / "four_bar.yaml"),
                                "compiled")
    settings = {"t_end": 0.5, "rtol": 1e-5, "atol": 1e-7}
    first = casmech.analyze(functions, **settings)
    assert first.metadata["integrator"] == "dop853" and first.metadata["cut_joints"]
    for result in (casmech.analyze(functions, **settings), _fresh(functions, **settings)):
        _same(result, first)


def test_a_formulation_registered_over_joint_is_run_by_a_kept_plan(functions):
    """The plan's prepared run is the built-in formulation's: once another entry is
    registered as "joint" (here the built-in's class subclassed: formulation_run's generic
    run), the same analysis runs it, and again the built-in once that is back."""
    from casmech.formulations.builtin import JointCoordinates
    from casmech.formulations.registry import FORMULATIONS

    class Generic(JointCoordinates):
        pass

    settings = BASE | {"formulation": "joint"}
    built_in = FORMULATIONS["joint"]
    own = casmech.analyze(functions, **settings)
    FORMULATIONS.register(Generic("joint"))
    try:
        generic = casmech.analyze(functions, **settings)
        _same(generic, _fresh(functions, **settings))
    finally:
        FORMULATIONS.register(built_in)
    assert "tree" in own.metadata and "tree" not in generic.metadata  # the generic run's
    _same(casmech.analyze(functions, **settings), own)


def _partial(functions, monkeypatch):
    """The partial Result of a run of BASE that fails after its first row (the plan kept by
    a run before it)."""
    from casmech.errors import AnalysisError
    from casmech.runtime import joint_run

    def failing(*args, **kwargs):
        raise AnalysisError("failed on purpose")

    monkeypatch.setattr(joint_run, "drive", failing)
    with pytest.raises(AnalysisError) as failed:
        casmech.analyze(functions, **BASE)
    return failed.value.partial


def test_a_partial_result_owns_its_times(functions, monkeypatch):
    """A run that fails after its first row: the Result's times are its own (writing them
    leaves the kept grid of the next run alone)."""
    base = casmech.analyze(functions, **BASE)
    partial = _partial(functions, monkeypatch)
    assert len(partial.t) == 1
    partial.t[:] = 7.0  # the caller's own array
    monkeypatch.undo()
    _same(casmech.analyze(functions, **BASE), base)


def test_a_partial_results_first_row_is_its_own(functions, monkeypatch):
    """A run that fails after its first row: its states are the run's own (the kept row at
    t0 handed out as a copy), so writing them leaves the next run's first row alone."""
    casmech.analyze(functions, **BASE)
    partial = _partial(functions, monkeypatch)
    for name in STATES[1:]:
        getattr(partial, name)[:] = 7.0  # the caller's own arrays
    monkeypatch.undo()
    _same(casmech.analyze(functions, **BASE), _fresh(functions, **BASE))


def test_a_prepared_runs_dop853_is_looked_up_by_its_first_call_only(functions, monkeypatch):
    """The integrator of a prepared run finds its DOP853 once (then kept: its loop and
    options are final by then); the runs give the rows of a fresh workspace."""
    from casmech.runtime import joint_dynamics

    looked, original = [], joint_dynamics.dop853_of

    def dop853_of(*args, **kwargs):
        looked.append(args[3])
        return original(*args, **kwargs)

    monkeypatch.setattr(joint_dynamics, "dop853_of", dop853_of)
    settings = BASE | {"method": "dop853", "output_step": 0.01}
    runs = [casmech.analyze(functions, **settings) for _ in range(3)]
    assert len(looked) == 1 and runs[0].metadata["integrator"] == "dop853"
    expected = _fresh(functions, **settings)
    for result in runs:
        _same(result, expected)


def test_the_kept_first_row_is_checked_once_and_refused_on_every_run(functions, monkeypatch):
    """The row at t0 of a kept start is checked when it is kept: the runs' Results check
    their blocks only, and a first row that is not finite is refused (NonFinite at t0, no
    rows) on every run, the repeated ones too."""
    from casmech.runtime import joint_recorder, results
    from casmech.runtime.nonfinite import NonFinite

    checked, original = [], results.check_states

    def check_states(times, *states):
        checked.append(len(times))
        return original(times, *states)

    monkeypatch.setattr(results, "check_states", check_states)
    workspace = Workspace(functions)
    for _ in range(3):
        casmech.analyze(functions, workspace=workspace, **BASE)
    assert checked == [30, 30, 30]  # (the block of each run; the row at t0 when kept)

    rows = joint_recorder.Recorder.rows

    def first_row_nan(self, times, states, algebraic):
        found = rows(self, times, states, algebraic)
        if len(times) == 1:
            found[2][0, 0] = np.nan  # q_ddot at t0
        return found

    monkeypatch.setattr(joint_recorder.Recorder, "rows", first_row_nan)
    poisoned = Workspace(functions)
    for _ in range(2):
        with pytest.raises(NonFinite) as refused:
            casmech.analyze(functions, workspace=poisoned, **BASE)
        assert len(refused.value.partial) == 0 and refused.value.partial.status == "failed"
