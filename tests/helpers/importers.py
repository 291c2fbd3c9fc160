"""Shared helpers of the importer tests: import a file, load/compile/run the YAML it gives."""

from __future__ import annotations

import casadi as ca
import numpy as np

import casmech
from casmech.importers import import_file
from tests.conftest import ROOT, Table

DECKS = ROOT / "tests" / "reference" / "chrono_adams" / "adams_models"
DATA = ROOT / "tests" / "data"
G = 9.80665


def imported(path, overrides=None):
    """(YAML text, warnings, compiled functions) of an imported file."""
    text, warnings = import_file(path)
    model = casmech.loads(text, file=f"{path}.yaml", overrides=overrides)
    return text, warnings, casmech.compile(model)


def run(functions, **kwargs) -> Table:
    result = casmech.analyze(functions, **kwargs)
    return Table(*casmech.results_table(functions, result))


def integrate(state, ode, x0, times, name="reference"):
    """CVODES at 1e-13 on an explicit ODE (an independent reference for casmech's DAE)."""
    solver = ca.integrator(name, "cvodes", {"x": state, "ode": ode}, 0.0, list(times[1:]),
                           {"reltol": 1e-13, "abstol": 1e-14, "max_num_steps": 100000})
    path = np.array(solver(x0=x0)["xf"].full())
    return np.column_stack([np.asarray(x0, float), path])
