"""backends.background: a cache miss of `--mode auto` (casmech.compile's default) runs
interpreted and builds the model's library in a detached process, so that the next call loads it
compiled; one build per library per process, one at a time per cache, none with
CASMECH_BACKGROUND_BUILD=0 (the test session's setting, tests/conftest.py)."""

import numpy as np
from filelock import FileLock

import casmech
from casmech.backends import background, codegen, library
from tests.conftest import MODELS
from tests.helpers.background import finished
from tests.helpers.codegen import counted_builds


def test_a_cache_miss_runs_interpreted_and_the_next_call_compiled(building, tmp_path,
                                                                   monkeypatch):
    """The double pendulum, a tree run in joint coordinates: the first default call is
    interpreted and starts the build; after it, the default call is compiled, its run builds
    nothing more (the child ran the dynamics over one output step, which built the joint
    system's library too) and gives the interpreted run's table."""
    model = casmech.load(MODELS / "double_pendulum.yaml")
    first = casmech.compile(model)
    assert codegen.mode_of(first) == "interpreted"
    assert len(background._children) == 1
    assert finished() == [0]
    assert not list((tmp_path / "tmp").glob("casmech-background-*"))  # the pickle is deleted
    # its marker removed: a later run's check (background.running) takes no lock
    assert not list(building.glob(f"*{background.BUILDING}"))
    second = casmech.compile(model)
    assert codegen.mode_of(second) == "compiled"
    builds = counted_builds(monkeypatch, library)
    compiled = casmech.analyze(second, t_end=0.5)
    assert builds == []  # everything the compiled run reads was built behind the first
    interpreted = casmech.analyze(first, t_end=0.5)
    _, expected = casmech.results_table(first, interpreted)
    _, got = casmech.results_table(second, compiled)
    # the same SX graphs evaluated by C and by CasADi's virtual machine: the same steps, the
    # states to within the integrator's roundoff
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)


def test_one_build_per_library_per_process(building):
    model = casmech.load(MODELS / "pendulum.yaml")
    for _ in range(3):
        assert codegen.mode_of(casmech.compile(model)) == "interpreted"
    assert len(background._children) == 1
    assert finished() == [0]
    assert codegen.mode_of(casmech.compile(model)) == "compiled"
    assert len(background._children) == 1  # a hit starts nothing


def test_turned_off_builds_nothing(building, monkeypatch):
    monkeypatch.setenv(background.ENVIRONMENT, "0")
    model = casmech.load(MODELS / "pendulum.yaml")
    assert codegen.mode_of(casmech.compile(model)) == "interpreted"
    assert background._children == []
    assert not building.exists()


def test_one_build_at_a_time_per_cache(building):
    """A child that finds the cache's background lock held leaves without building (and
    without leaving its pickle behind); the next miss of the same process does not retry."""
    model = casmech.load(MODELS / "pendulum.yaml")
    building.mkdir(parents=True)
    with FileLock(str(building / background.BACKGROUND_LOCK)):
        assert codegen.mode_of(casmech.compile(model)) == "interpreted"
        assert finished() == [0]
    assert not codegen.is_cached(model)
    assert codegen.mode_of(casmech.compile(model)) == "interpreted"
    assert len(background._children) <= 1


def test_the_command_line_builds_behind_its_run(building, tmp_path):
    """`casmech run` of a cache miss: the run is interpreted (its metadata says so), the next
    run compiled."""
    import json

    from casmech.cli import main

    model = MODELS / "pendulum.yaml"
    out = tmp_path / "out"
    assert main(["run", str(model), "--t-end", "0.2", "--out", str(out), "--quiet"]) == 0
    assert json.loads((out / "metadata.json").read_text())["mode"] == "interpreted"
    assert finished() == [0]
    assert main(["run", str(model), "--t-end", "0.2", "--out", str(out), "--quiet"]) == 0
    assert json.loads((out / "metadata.json").read_text())["mode"] == "compiled"


def test_a_build_under_way_is_a_miss(building):
    """The bundle published while the child still builds the rest: auto stays interpreted (no
    run waits for a background build), and is compiled once the marker's lock is free."""
    from casmech.backends import cache

    model = casmech.load(MODELS / "pendulum.yaml")
    casmech.compile(model, "compiled")
    (entry,) = cache.entries(building)  # the bundle, as a background child publishes it first
    with FileLock(str(building / f"{entry.name}{background.BUILDING}")):
        assert background.running(entry.name, building)
        assert codegen.auto_mode(model) == "interpreted"
    assert not background.running(entry.name, building)
    assert codegen.auto_mode(model) == "compiled"


def test_a_model_that_cannot_be_handed_over_is_not_built(building, tmp_path):
    """Nothing the background build fails on reaches the run that asked: an object pickle
    refuses starts no process and leaves no file behind."""
    def local():  # a local function: pickle refuses it
        return 0

    assert background.start(local, None, building, "key") is None
    assert background._children == []
    assert not list((tmp_path / "tmp").glob("casmech-background-*"))
