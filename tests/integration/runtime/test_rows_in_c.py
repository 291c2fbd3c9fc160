"""A compiled joint tree's results rows go through one C loop over the rows
(backends.rows_loop, runtime.joint_recorder): the same table as casadi's map over columns of
the same compiled function (ColumnCall, the path of every other bundle)."""

import numpy as np

import casmech
from casmech.backends import rows_loop
from casmech.backends.rows_loop import RowsCall
from casmech.runtime import workspace
from casmech.runtime.results import row
from tests.conftest import MODELS, ROOT

# two bars hanging from spherical joints, no parameters: its library compiles the results row
CHAIN = ROOT / "benchmarks" / "models" / "chain2.yaml"


def _table(functions):
    result = casmech.analyze(functions, "dynamics", t_end=0.5, rtol=1e-6, atol=1e-8)
    return np.asarray(casmech.results_table(functions, result)[1], float)


def test_the_rows_loop_gives_the_maps_table(quick_builds, monkeypatch):
    model = casmech.load(MODELS / "double_pendulum.yaml")
    functions = casmech.compile(model, "compiled")
    table = _table(functions)
    calls = workspace.default(functions).store("joint_motion_maps").values()
    assert [type(call) for call in calls] == [RowsCall]
    # without the C loop (a new bundle: calls are kept per bundle): casadi's map
    monkeypatch.setattr(rows_loop, "rows_call", lambda function: None)
    again = casmech.compile(model, "compiled")
    mapped = _table(again)
    calls = workspace.default(again).store("joint_motion_maps").values()
    assert [type(call).__name__ for call in calls] == ["ColumnCall"]
    # the same compiled code on the same states
    np.testing.assert_array_equal(table, mapped)
    assert table.shape[0] > 10 and np.isfinite(table).all()


def test_the_loops_solved_rows_in_c(quick_builds, monkeypatch):
    """A closed loop's rows, their multipliers solved at each state
    (runtime.joint_rows.LoopRows over the library's joint_solved_motion; a model without
    parameters, whose library holds it): the same table as the map's."""
    model = casmech.load(ROOT / "benchmarks" / "models" / "four_bar.yaml")
    functions = casmech.compile(model, "compiled")
    table = _table(functions)
    rows = list(workspace.default(functions).store("joint_loop_rows").values())
    assert [type(found.call) for found in rows] == [RowsCall]
    monkeypatch.setattr(rows_loop, "rows_call", lambda function: None)
    again = casmech.compile(model, "compiled")
    mapped = _table(again)
    rows = list(workspace.default(again).store("joint_loop_rows").values())
    assert [type(found.call).__name__ for found in rows] == ["ColumnCall"]
    np.testing.assert_array_equal(table, mapped)


def test_the_singular_pose_check_in_c_finds_the_flat_poses(quick_builds, monkeypatch):
    """A compiled loop's singular-pose check (runtime.singular_poses) runs its compiled
    log-determinants in the rows' C loop: IFToMM A02 passes a flat pose in its first second;
    the check finds it, and the log-determinants are casadi's map's of the same function."""
    from casmech.runtime import singular_poses
    from casmech.runtime.buffers import ColumnCall
    from tests.helpers.reference_data import VALIDATION_MODELS

    model = casmech.load(VALIDATION_MODELS / "iftomm_a02_four_bar_N2.yaml")
    functions = casmech.compile(model, "compiled")
    result = casmech.analyze(functions, "dynamics", t_end=1.0, rtol=1e-7, atol=1e-9)
    _, compiled = singular_poses._entries(functions, None)["compiled"]
    assert type(compiled.call) is RowsCall
    poses = result.metadata["singular_poses"]
    assert len(poses) == 1 and 0.6 < poses[0]["t"] < 0.8  # the first flat pose, at ~0.71 s
    mapped = ColumnCall(compiled.call.function)(  # with a parametric library's data
        result.t[None, :], result.q.T, *(d[:, None] for d in compiled.data))[0].ravel()
    # the same compiled code on the same rows
    np.testing.assert_array_equal(compiled(result.t, result.q), mapped)
    # without the C loop: casadi's map, the same poses
    monkeypatch.setattr(rows_loop, "rows_call", lambda function: None)
    again = casmech.compile(model, "compiled")
    found = casmech.analyze(again, "dynamics", t_end=1.0, rtol=1e-7, atol=1e-9)
    assert type(singular_poses._entries(again, None)["compiled"][1].call) is ColumnCall
    assert found.metadata["singular_poses"] == poses


def test_the_results_table_is_the_maps_table(quick_builds, monkeypatch):
    """runtime.results.table evaluates the compiled results row through runtime.row_calls.over_rows
    (the rows' C loop where it takes the function, else casadi's map), then writes the joints'
    reactions in their frames: the same table as the map over columns, reaction frames and
    all."""
    model = casmech.load(CHAIN)
    functions = casmech.compile(model, "compiled")
    result = casmech.analyze(functions, "dynamics", t_end=0.5, rtol=1e-6, atol=1e-8)
    frames = {"j2": "body_i"}
    table = casmech.results_table(functions, result, reaction_frames=frames)[1]
    calls = workspace.default(functions).store("results_row").values()
    assert [type(call) for call in calls] == [RowsCall]
    monkeypatch.setattr(rows_loop, "rows_call", lambda function: None)
    again = casmech.compile(model, "compiled")
    mapped = casmech.results_table(again, result, reaction_frames=frames)[1]
    calls = workspace.default(again).store("results_row").values()
    assert [type(call).__name__ for call in calls] == ["ColumnCall"]
    # the same compiled code on the same states
    np.testing.assert_array_equal(table, mapped)
    # row by row, numerically (runtime.results.row: the bundle's functions one call each)
    names, plain = casmech.results_table(functions, result)
    assert plain.shape == (len(result), len(names))
    for k in (0, len(result) // 2, len(result) - 1):
        expected = row(functions, result.times[k], result.q[k], result.q_dot[k],
                       result.q_ddot[k], result.lam[k])
        # the same terms through another graph: equal to rounding
        np.testing.assert_allclose(plain[k], expected, rtol=1e-12, atol=1e-12)
