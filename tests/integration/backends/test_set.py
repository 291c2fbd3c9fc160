"""CompiledModel.set (backends.rebind): a compiled parametric model moved to other parameter
values runs without a build (counted at the cache's build callable) with the physics of those
values (closed-form periods, and the model loaded with them); an interpreted one is rebuilt;
a value that changes the structure is a located error naming the parameter."""

import warnings

import numpy as np
import pytest

import casmech
from casmech.backends import parametric, rebind
from casmech.errors import ModelError, UsageError
from tests.integration.backends.test_parametric import MODEL, expected, period


@pytest.fixture
def model_file(tmp_path):
    path = tmp_path / "oscillators.yaml"
    path.write_text(MODEL)
    return path


def motion(functions, **settings) -> dict[str, np.ndarray]:
    result = casmech.analyze(functions, **settings)
    names, values = casmech.results_table(functions, result)
    return {name: values[:, k] for k, name in enumerate(names)}


def test_set_rebinds_the_compiled_library_without_a_build(model_file, toolchain, builds):
    compiled = casmech.compile(casmech.load(model_file), "compiled")
    assert compiled.library is not None  # the parametric library, bound to the file's values
    motion(compiled, t_end=0.01)  # what a first run of this structure builds (joint library)
    first_builds = len(builds)
    heavier = compiled.set(m=3)
    rows = motion(heavier)
    assert len(builds) == first_builds  # nothing generated, nothing built
    assert heavier.library == compiled.library and heavier is not compiled
    spring, pendulum = expected({"m": 3.0})
    # 1e-4: zero crossings interpolated between rows 2 ms apart (test_parametric's bound)
    np.testing.assert_allclose(period(rows["t"], rows["block.x"] - 1.0), spring,
                               rtol=1e-4, atol=0)
    np.testing.assert_allclose(period(rows["t"], rows["bob.x"] - 5.0), pendulum,
                               rtol=1e-4, atol=0)
    # the model loaded with m = 3 and run interpreted: the same motion within the
    # integrator's tolerance (rtol 1e-10 on positions of order 1 over 4 s)
    reference = motion(casmech.compile(casmech.load(model_file, {"m": "3"})))
    for column in ("block.x", "block.vx", "bob.x", "slide.fx"):
        np.testing.assert_allclose(rows[column], reference[column], rtol=0, atol=1e-6)
    # the original is unchanged: its values, its motion (the file's m = 2)
    assert compiled.parameters["m"] == 2.0 and heavier.parameters["m"] == 3.0
    original = motion(compiled, t_end=2.0)
    np.testing.assert_allclose(period(original["t"], original["block.x"] - 1.0),
                               expected({})[0], rtol=1e-4, atol=0)
    assert len(builds) == first_builds


def test_set_takes_a_mapping_texts_with_units_and_several_values(model_file, toolchain, builds):
    compiled = casmech.compile(casmech.load(model_file), "compiled")
    before = len(builds)
    moved = compiled.set({"L": "2000 mm"}, k=150)
    assert moved.parameters["L"] == 2.0 and moved.parameters["k"] == 150.0
    rows = motion(moved, t_end=6.0)
    spring, pendulum = expected({"L": 2.0, "k": 150.0})
    # as above: crossings interpolated between 2 ms rows
    np.testing.assert_allclose(period(rows["t"], rows["block.x"] - 1.0), spring,
                               rtol=1e-4, atol=0)
    np.testing.assert_allclose(period(rows["t"], rows["bob.x"] - 5.0), pendulum,
                               rtol=1e-4, atol=0)
    assert len(builds) == before
    # values accumulate: set on the moved model keeps L = 2
    assert moved.set(m=1).parameters["L"] == 2.0


def test_set_rebuilds_an_interpreted_bundle(model_file, builds):
    interpreted = casmech.compile(casmech.load(model_file), "interpreted")
    moved = interpreted.set(m=3)
    assert moved.library is None and moved.mode == "interpreted"
    rows = motion(moved, t_end=1.0)
    reference = motion(casmech.compile(casmech.load(model_file, {"m": "3"}), "interpreted"),
                       t_end=1.0)
    for column in ("block.x", "bob.x", "slide.fx"):
        # the same functions and integrator: identical to round-off
        np.testing.assert_allclose(rows[column], reference[column], rtol=0, atol=1e-12)
    assert builds == []


def test_a_value_that_changes_the_structure_is_a_located_error(model_file, toolchain):
    compiled = casmech.compile(casmech.load(model_file), "compiled")
    with pytest.raises(UsageError) as error:
        compiled.set(theta0=0.0, k=120)  # theta0 = 0 puts the bob on the pivot's vertical
    message = str(error.value)
    assert message.startswith(f"{model_file}:3:")  # the key of theta0 in `parameters:`
    assert "'theta0' = 0.0" in message and "'k'" not in message.split("\n")[0].split("(")[0]
    # where the structure changes: the pivot's constraint on the bob, whose arm loses a
    # non-zero entry when theta0 = 0
    assert "changes the structure" in message and "'pivot'" in message
    assert "non-zero" in message
    assert "hint: casmech.compile(casmech.load(" in message
    # an interpreted bundle takes the value (it is rebuilt)
    moved = casmech.compile(casmech.load(model_file), "interpreted").set(theta0=0.0)
    assert moved.parameters["theta0"] == 0.0


def test_bad_names_and_values_are_model_errors(model_file):
    compiled = casmech.compile(casmech.load(model_file))
    with pytest.raises(ModelError) as error:
        compiled.set(mm=3)
    assert "error[E300]" in str(error.value) and "did you mean 'm'?" in str(error.value)
    with pytest.raises(ModelError) as error:
        compiled.set(m=-1)
    assert "error[E400] bodies[0].mass" in str(error.value)
    with pytest.raises(UsageError, match="takes a number or a text"):
        compiled.set(m=[1, 2])
    assert compiled.set() is compiled


def test_set_on_a_library_with_its_values_builds_another_and_warns(model_file, toolchain,
                                                                    builds, monkeypatch):
    """Over parametric.MAX_BODIES bodies the library holds its values: set compiles again."""
    monkeypatch.setattr(parametric, "MAX_BODIES", 0)
    compiled = casmech.compile(casmech.load(model_file), "compiled")
    assert compiled.library is None and casmech.backends.codegen.mode_of(compiled) == "compiled"
    before = len(builds)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        moved = compiled.set(m=3)
    assert any("builds another one" in str(w.message) for w in caught)
    assert len(builds) == before + 1
    rows = motion(moved, t_end=2.0)  # nearly two periods of 1.09 s: three crossings
    # 1e-4: as above
    np.testing.assert_allclose(period(rows["t"], rows["block.x"] - 1.0),
                               expected({"m": 3.0})[0], rtol=1e-4, atol=0)


def test_repr_is_one_line(model_file):
    text = repr(casmech.compile(casmech.load(model_file), "interpreted").set(m=3))
    assert text.startswith(
        "CompiledModel('two_oscillators': 2 bodies, 2 joints, 2 DOF; interpreted")
    assert "m=3" in text and "\n" not in text


def test_override_text_is_exact():
    value = 0.1 + 0.2
    assert float(rebind.override_text("m", value)) == value
    assert rebind.override_text("m", np.float32(2.5)) == "2.5"
    assert rebind.override_text("a", "30 deg") == "30 deg"
    with pytest.raises(UsageError):
        rebind.override_text("m", True)
