"""Runs of one bundle from several threads (runtime.workspace: a workspace's runs one at a
time): what a run keeps for the next (DOP853's C work vectors, the rows' C loop, solver
memories) is one set per workspace, and two threads writing it at once would give rows that
are not finite or a segmentation fault. Every threaded run equals the serial run bit for bit,
compiled (DOP853 and the rows in C) and interpreted (CVODES)."""

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import casmech
from tests.conftest import MODELS, ROOT


def _table(functions) -> np.ndarray:
    result = casmech.analyze(functions, "dynamics", t_end=0.5)
    return np.column_stack([result.times, result.q, result.q_dot, result.lam])


@pytest.mark.parametrize("mode", ["compiled", "interpreted"])
def test_threads_on_one_bundle_equal_the_serial_run(mode, request):
    if mode == "compiled":
        request.getfixturevalue("quick_builds")
    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"), mode)
    serial = _table(functions)
    with ThreadPoolExecutor(4) as pool:
        tables = list(pool.map(lambda _: _table(functions), range(16)))
    for table in tables:
        np.testing.assert_array_equal(table, serial)  # the same run: the same doubles


def test_threads_on_bundles_of_their_own_equal_the_serial_run(quick_builds):
    """Bundles compiled from one model share their library's functions: each bundle's
    workspace holds its own C work vectors, so their runs go on at once."""
    model = casmech.load(MODELS / "double_pendulum.yaml")
    bundles = [casmech.compile(model, "compiled") for _ in range(4)]
    serial = _table(bundles[0])
    with ThreadPoolExecutor(4) as pool:
        tables = list(pool.map(_table, bundles * 4))
    for table in tables:
        np.testing.assert_array_equal(table, serial)  # the same run: the same doubles


def test_results_tables_from_threads_equal_the_serial_table(quick_builds):
    """The results table of one bundle from several threads at once: its compiled row in the
    rows' C loop (one set of work vectors a workspace) is called by one thread at a time."""
    functions = casmech.compile(casmech.load(ROOT / "benchmarks" / "models" / "chain2.yaml"),
                                "compiled")
    result = casmech.analyze(functions, "dynamics", t_end=2.0)
    serial = casmech.results_table(functions, result)[1]
    with ThreadPoolExecutor(4) as pool:
        tables = list(pool.map(lambda _: casmech.results_table(functions, result)[1],
                               range(32)))
    for table in tables:
        np.testing.assert_array_equal(table, serial)  # the same rows: the same doubles
