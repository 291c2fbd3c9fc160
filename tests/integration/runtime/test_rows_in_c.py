"""A compiled joint tree's results rows go through one C loop over the rows
(backends.rows_loop, runtime.joint_recorder): the same table as casadi's map over columns of
the same compiled function (ColumnCall, the path of every other bundle)."""

import numpy as np

import casmech
from casmech.backends import rows_loop
from casmech.backends.rows_loop import RowsCall
from casmech.runtime import workspace
from tests.conftest import MODELS


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
