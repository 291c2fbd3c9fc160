"""Every model of the gallery that `casmech export` takes, exported and run by fmpy (Model
Exchange and Co-Simulation) against `casmech run`'s dynamics to t = 0.5 s (slow: about two
minutes of builds at -O0)."""

import pytest

import casmech
from casmech.errors import UsageError
from casmech.fmu.archive import Options, export
from tests.helpers.fmu import MODELS, assert_matches, outputs

pytestmark = pytest.mark.slow
T_END = 0.5
MODEL_FILES = sorted(MODELS.glob("*.yaml"))
# refused, with the reason: a payload held by basic constraints only and a nut held by a screw
# (a body floating in the tree, its rows cut), a gear (the FMU's equations take no coupling)
REFUSED = {"ocp_arm3d": "floating body", "lead_screw": "floating body",
           "gear_pair": "couplings of joint coordinates",
           "four_bar_released": "initial: values"}
# fmpy's CVODE gives up after 500 steps per output interval on the ball's stiff contact
NO_MODEL_EXCHANGE = {"bouncing_ball"}


def reference(model) -> dict[str, float]:
    functions = casmech.compile(model, "interpreted")
    result = casmech.analyze(functions, "dynamics", t_end=T_END, output_step=0.01, rtol=1e-10,
                             atol=1e-12)
    names, values = casmech.results_table(functions, result)
    return dict(zip(names, values[-1], strict=True))


def simulate(path, kind: str) -> dict[str, float]:
    from fmpy import simulate_fmu

    names = outputs(path)
    result = simulate_fmu(str(path), fmi_type=kind, stop_time=T_END, output_interval=0.01,
                          relative_tolerance=1e-12 if kind == "ModelExchange" else 1e-10,
                          output=names)
    return {name: float(result[name][-1]) for name in names}


@pytest.mark.parametrize("file", MODEL_FILES, ids=lambda f: f.stem)
def test_every_gallery_model(file, toolchain, tmp_path):
    from casmech.backends.build import Toolchain

    model = casmech.load(file)
    quick = Toolchain(toolchain.compiler, ("-O0", "-Wall", "-Werror"), toolchain.jobs)
    if file.stem in REFUSED:
        with pytest.raises(UsageError, match=REFUSED[file.stem]):
            export(model, tmp_path / "model.fmu", Options(toolchain=quick))
        return
    path = export(model, tmp_path / "model.fmu", Options(toolchain=quick)).path
    expected = reference(model)
    for kind in ("ModelExchange", "CoSimulation"):
        if kind == "ModelExchange" and file.stem in NO_MODEL_EXCHANGE:
            continue
        assert_matches(simulate(path, kind), expected)
