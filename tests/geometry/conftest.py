"""Fixtures of the geometry tests (as tests/compiler/conftest.py)."""

import numpy as np
import pytest

SEEDS = [0, 1, 2, 3, 4]


@pytest.fixture(params=SEEDS, ids=lambda s: f"seed{s}")
def rng(request) -> np.random.Generator:
    """A seeded generator; every test using it runs once per seed."""
    return np.random.default_rng(request.param)
