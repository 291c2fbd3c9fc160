"""backends.handover through casmech.compile's default: the functions of an auto miss run
interpreted while their library is built behind, and compiled from the first analysis that
starts after the build has published it; explicit modes, the build turned off, a failed build
and a caller's workspace keep them interpreted; `set` values carry over."""

import numpy as np
import pytest
from filelock import FileLock

import casmech
from casmech.backends import background, codegen, library
from casmech.runtime.workspace import Workspace
from tests.conftest import MODELS
from tests.helpers.background import finished
from tests.helpers.codegen import counted_builds


def test_the_same_functions_run_compiled_once_the_build_is_published(building, monkeypatch):
    """The double pendulum (a tree in joint coordinates, a parametric library): the first
    analysis is interpreted and one build starts; once it has exited, the next analysis of the
    same functions is compiled, builds nothing, starts no other build, and gives the first
    one's table; the functions themselves stay interpreted (SX) for symbolic use. (Method
    dop853 named: under auto an interpreted run takes Adams and a compiled one DOP853,
    docs/decisions/method-auto.md, results that differ within the tolerance.)"""
    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    first = casmech.analyze(functions, t_end=0.5, method="dop853")
    assert first.metadata["mode"] == "interpreted"
    assert len(background._children) == 1
    assert finished() == [0]
    builds = counted_builds(monkeypatch, library)
    second = casmech.analyze(functions, t_end=0.5, method="dop853")
    assert second.metadata["mode"] == "compiled"
    assert codegen.mode_of(second.functions) == "compiled"
    assert builds == []  # the library and what its run reads were built behind
    assert len(background._children) == 1 and len(background._started) == 1
    assert codegen.mode_of(functions) == "interpreted"
    assert casmech.analyze(functions, t_end=0.5).functions is second.functions  # loaded once
    _, expected = casmech.results_table(functions, first)
    _, got = casmech.results_table(functions, second)
    # the same SX graphs evaluated by C and by CasADi's virtual machine: the same steps, the
    # states to within the integrator's roundoff
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)


def test_functions_compiled_again_while_it_builds_hand_over_too(building):
    """A second casmech.compile of the model while this process's build of its library is
    under way, its first part published (the child holds the key's BUILDING lock: held here
    after the child is done), is interpreted and follows the same build: its analyses run
    compiled once the child has exited, and no second build starts."""
    model = casmech.load(MODELS / "double_pendulum.yaml")
    casmech.analyze(casmech.compile(model), t_end=0.5)
    assert finished() == [0]
    (key,) = background._started
    with FileLock(str(building / f"{key}{background.BUILDING}")):
        again = casmech.compile(model)
    assert codegen.mode_of(again) == "interpreted"
    assert casmech.analyze(again, t_end=0.5).metadata["mode"] == "compiled"
    assert len(background._children) == 1


@pytest.mark.parametrize("mode", ["interpreted", "compiled"])
def test_an_explicit_mode_never_hands_over(building, mode):
    """Functions compiled in an explicit mode run in it whatever a build of the same library
    started by an auto call does."""
    model = casmech.load(MODELS / "pendulum.yaml")
    casmech.compile(model)  # an auto miss: the build starts
    pinned = casmech.compile(model, mode)
    assert pinned.handover is None
    assert finished() == [0]
    assert casmech.analyze(pinned, t_end=0.2).metadata["mode"] == mode


def test_the_build_turned_off_never_hands_over(building, monkeypatch):
    monkeypatch.setenv(background.ENVIRONMENT, "0")
    model = casmech.load(MODELS / "pendulum.yaml")
    functions = casmech.compile(model)
    assert functions.handover is None
    casmech.compile(model, "compiled")  # the library in the cache: nothing moves to it
    assert casmech.analyze(functions, t_end=0.2).metadata["mode"] == "interpreted"


def test_a_killed_build_leaves_the_functions_interpreted(building):
    """A child killed before it published the library: analyses go on interpreted without an
    error, and the handover, decided, does not take a library published later by others."""
    model = casmech.load(MODELS / "pendulum.yaml")
    functions = casmech.compile(model)
    (child,) = background._children
    child.kill()
    assert finished() != [0]
    assert casmech.analyze(functions, t_end=0.2).metadata["mode"] == "interpreted"
    casmech.compile(model, "compiled")
    assert codegen.is_cached(model)
    assert casmech.analyze(functions, t_end=0.2).metadata["mode"] == "interpreted"


def test_a_build_that_left_for_another_leaves_the_functions_interpreted(building):
    """A child that found the cache's background lock held left without building (exit 0, no
    library): the functions stay interpreted."""
    model = casmech.load(MODELS / "pendulum.yaml")
    building.mkdir(parents=True)
    with FileLock(str(building / background.BACKGROUND_LOCK)):
        functions = casmech.compile(model)
        assert finished() == [0]
    assert not codegen.is_cached(model)
    assert casmech.analyze(functions, t_end=0.2).metadata["mode"] == "interpreted"


def test_set_values_carry_over(building):
    """Functions moved to another damping before the build ends run compiled at that damping
    once it is published: the table of an interpreted run at that value, not the file's
    (method dop853 named: auto would run Adams interpreted and DOP853 compiled)."""
    path = MODELS / "estimate_pendulum.yaml"
    functions = casmech.compile(casmech.load(path))
    damped = functions.set(c=0.9)
    assert damped.handover is not None
    assert finished() == [0]
    result = casmech.analyze(damped, t_end=1.0, method="dop853")
    assert result.metadata["mode"] == "compiled"
    assert codegen.mode_of(damped) == "interpreted"
    _, got = casmech.results_table(damped, result)
    reference = casmech.compile(casmech.load(path, overrides={"c": "0.9"}), "interpreted")
    _, expected = casmech.results_table(reference, casmech.analyze(reference, t_end=1.0,
                                                                   method="dop853"))
    _, undamped = casmech.results_table(functions, casmech.analyze(functions, t_end=1.0,
                                                                   method="dop853"))
    # C and CasADi's virtual machine over the same graphs: roundoff through the integrator
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)
    assert np.max(np.abs(got - undamped)) > 1e-3  # the value set is the one that ran


def test_a_callers_workspace_keeps_the_functions_it_serves(building):
    """A workspace given by the caller serves the interpreted functions: the run stays on
    them (no mix of the two bundles' kept entries); without it the run is compiled."""
    functions = casmech.compile(casmech.load(MODELS / "pendulum.yaml"))
    assert finished() == [0]
    workspace = Workspace(functions)
    assert casmech.analyze(functions, t_end=0.2, workspace=workspace
                           ).metadata["mode"] == "interpreted"
    assert casmech.analyze(functions, t_end=0.2).metadata["mode"] == "compiled"
