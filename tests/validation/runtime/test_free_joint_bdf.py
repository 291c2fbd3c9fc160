"""BDF on a tree whose mass matrix is symmetric in value but not in structure (the imported
gymnasium ant: a free root joint and four legs), against Adams on the same model. BDF's Newton
matrix comes from the RNEA identity, whose Cholesky factor needs a structurally symmetric M
(formulations.rnea.forward_derivatives)."""

import warnings
from pathlib import Path

import numpy as np
import pytest

import casmech

gymnasium = pytest.importorskip("gymnasium")


@pytest.fixture(scope="module")
def ant():
    from casmech.importers.emit import to_yaml
    from casmech.importers.mjcf import import_mjcf

    path = Path(gymnasium.__file__).parent / "envs/mujoco/assets/ant.xml"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the import's notes on what casmech leaves out
        return casmech.loads(to_yaml(import_mjcf(path)), file=f"{path}.yaml")


def test_bdf_runs_the_ant_as_adams_does(ant):
    functions = casmech.compile(ant, "interpreted")
    tables = {}
    for method in ("adams", "bdf"):
        result = casmech.analyze(functions, "dynamics", t_end=0.05, output_step=0.01,
                                 rtol=1e-9, atol=1e-11, method=method)
        assert result.metadata["method"] == method
        tables[method] = casmech.results_table(functions, result)[1]
    # two integrators at rtol 1e-9 over 0.05 s of a falling ant: equal to well within 1e-6
    np.testing.assert_allclose(tables["bdf"], tables["adams"], rtol=0, atol=1e-6)
