"""The MJCF files shipped in gymnasium and dm_control (read from the installed packages,
skipped without them): those casmech's elements express import, load and run; the others are
refused with a located error that says why."""

from __future__ import annotations

from pathlib import Path

import pytest

import casmech
from casmech.errors import ModelError
from casmech.importers.emit import to_yaml
from casmech.importers.mjcf import import_mjcf

# refused, with the reason (two hinges of one body on lines that do not meet: no casmech joint)
REFUSED = {"dm_control/humanoid.xml": "body[right_foot]: the joints of body 'right_foot'",
           "dm_control/dog.xml": "body[scapula_L]: the joints of body 'scapula_L'"}
EMPTY = {"dm_control/lqr.xml"}  # a template: bodies are added by dm_control's code
HEAVY = {"dm_control/humanoid_CMU.xml", "dm_control/quadruped.xml", "dm_control/stacker.xml",
         "dm_control/manipulator.xml", "gymnasium/ant.xml"}  # several seconds each


def models() -> list:
    found = []
    for package, folder in (("gymnasium", "envs/mujoco/assets"), ("dm_control", "suite")):
        try:
            module = __import__(package)
        except ImportError:
            continue
        for path in sorted((Path(module.__file__).parent / folder).glob("*.xml")):
            key = f"{package}/{path.name}"
            marks = [pytest.mark.slow] if key in HEAVY else []
            found.append(pytest.param(path, key, id=key, marks=marks))
    return found or [pytest.param(None, None, marks=pytest.mark.skip(
        reason="neither gymnasium nor dm_control is installed"))]


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("path, key", models())
def test_package_models_import_and_run(path, key):
    if key in REFUSED:
        with pytest.raises(ModelError) as caught:
            import_mjcf(path)
        (diagnostic,) = caught.value.diagnostics
        assert diagnostic.code == "E103" and REFUSED[key] in diagnostic.format()
        assert str(path) in diagnostic.format()  # located in the package's file
        return
    imported = import_mjcf(path)
    model = casmech.loads(to_yaml(imported), file=f"{path}.yaml")
    if key in EMPTY:
        assert model.bodies == ()
        return
    assert model.bodies
    functions = casmech.compile(model)
    result = casmech.analyze(functions, "dynamics", t_end=0.02, output_step=0.01)
    names, values = casmech.results_table(functions, result)
    assert values.shape[0] == 3 and abs(values[-1, 0] - 0.02) < 1e-12
