"""Fixtures of the FMU tests: fmpy (the test extra), a C compiler, a private compiled-model
cache, and helpers that run an FMU with fmpy and a model with casmech to compare them."""

from pathlib import Path

import numpy as np
import pytest

import casmech
from casmech.backends import codegen
from casmech.fmu.archive import Options, export

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "models"
T_END = 1.0
STEP = 0.01
# casmech's reference runs: tighter than any FMU run compared with them
RTOL, ATOL = 1e-10, 1e-12


@pytest.fixture(autouse=True)
def private_cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "cache"))


@pytest.fixture(scope="session")
def toolchain() -> codegen.Toolchain:
    """-O1 as `casmech export` builds by default, with -Wall -Werror: the FMU's C, generated
    and written, compiles cleanly; without a compiler the tests skip."""
    pytest.importorskip("fmpy")
    chain = codegen.Toolchain(flags=("-O1", "-Wall", "-Werror"))
    if not codegen.available(chain):
        pytest.skip(f"no C compiler '{chain.compiler}'")
    return chain


def build(model, folder: Path, toolchain, name: str = "model", **options) -> Path:
    """The model's FMU in `folder`."""
    return export(model, folder / f"{name}.fmu", Options(toolchain=toolchain, **options)).path


def reference(model, analysis: str = "dynamics") -> dict[str, float]:
    """Every results column of `casmech run` (the interpreted bundle) at T_END."""
    functions = casmech.compile(model, "interpreted")
    result = casmech.analyze(functions, analysis, t_end=T_END, output_step=STEP, rtol=RTOL,
                             atol=ATOL)
    names, values = casmech.results_table(functions, result)
    assert abs(values[-1, 0] - T_END) < 1e-12
    return dict(zip(names, values[-1], strict=True))


def outputs(path: Path) -> list[str]:
    from fmpy import read_model_description

    return [v.name for v in read_model_description(str(path)).modelVariables
            if v.causality == "output"]


def simulate(path: Path, kind: str, **options) -> dict[str, float]:
    """Every output of the FMU at T_END: Model Exchange by fmpy's CVODE, Co-Simulation by
    the FMU's own integrator."""
    from fmpy import simulate_fmu

    names = outputs(path)
    tolerance = {"ModelExchange": 1e-12, "CoSimulation": 1e-10}[kind]
    result = simulate_fmu(str(path), fmi_type=kind, stop_time=T_END, output_interval=STEP,
                          relative_tolerance=tolerance, output=names, **options)
    assert abs(result["time"][-1] - T_END) < 1e-9
    return {name: float(result[name][-1]) for name in names}


POSE = (".x", ".y", ".z", ".e0", ".e1", ".e2", ".e3")


def assert_matches(got: dict[str, float], expected: dict[str, float]) -> None:
    """The FMU's outputs against casmech's columns at T_END: positions and Euler parameters
    to 1e-6 absolute, every column (velocities, accelerations, reactions, energy) to 1e-6
    relative to 1 + its size."""
    names = sorted(got)
    assert names and set(names) <= set(expected)
    pose = [n for n in names if n.endswith(POSE)]
    # 1e-6 m: the issue's bar; the runs' own errors at their tolerances are ~1e-9
    np.testing.assert_allclose([got[n] for n in pose], [expected[n] for n in pose],
                               rtol=0, atol=1e-6)
    scale = np.array([1.0 + abs(expected[n]) for n in names])
    error = np.abs(np.array([got[n] - expected[n] for n in names])) / scale
    worst = names[int(np.argmax(error))]
    # 1e-6 relative: accelerations and reactions carry the integrators' errors times the
    # ODE's stiffness; measured at most 3e-7 (a four-bar's acceleration)
    np.testing.assert_allclose(error, 0.0, rtol=0, atol=1e-6, err_msg=f"worst: {worst}")


def slave(path: Path, folder: Path):
    """(an instantiated fmpy FMU2Slave of the FMU unpacked into `folder`, its value
    references by name)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    description = read_model_description(str(path))
    refs = {v.name: v.valueReference for v in description.modelVariables}
    instance = FMU2Slave(guid=description.guid,
                         unzipDirectory=extract(str(path), unzipdir=str(folder)),
                         modelIdentifier=description.coSimulation.modelIdentifier)
    instance.instantiate()
    return instance, refs
