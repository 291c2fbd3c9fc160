"""One real run shared by the output tests: the slider-crank for 0.1 s, written as CSV and HDF5."""

import time
from types import SimpleNamespace

import pytest

from casmech import cli
from tests.conftest import MODELS

SLIDER = MODELS / "slider_crank.yaml"


@pytest.fixture(scope="session")
def slider_run(tmp_path_factory):
    """casmech run (in-process) with a parameter override; the wall time around it bounds the
    timings it records."""
    out = tmp_path_factory.mktemp("slider")
    start = time.perf_counter()
    code = cli.main(["run", str(SLIDER), "--out", str(out), "--t-end", "0.1",
                     "--set", "omega=3", "--format", "csv,hdf5"])
    wall = time.perf_counter() - start
    assert code == 0
    return SimpleNamespace(out=out, model=SLIDER, wall=wall)
