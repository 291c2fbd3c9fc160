"""Shared fixtures: paths to the example models, running a model through the API."""

from pathlib import Path

import numpy as np
import pytest

import casmech

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"


class Table:
    """Results table with column access by contract name: table["bar.x"]."""

    def __init__(self, names, values):
        self.names, self.values = list(names), np.asarray(values)

    def __getitem__(self, name):
        return self.values[:, self.names.index(name)]


def run_model(path, **kwargs):
    functions = casmech.compile(casmech.load(path))
    result = casmech.analyze(functions, **kwargs)
    return functions, Table(*casmech.results_table(functions, result))


@pytest.fixture(scope="session")
def models_dir():
    return MODELS
