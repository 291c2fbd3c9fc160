"""The Workspace (casmech.runtime.workspace): a bundle of system functions is immutable, what
runs derive from it lives in a workspace owned by the caller (by default one per bundle, gone
with it), bounded, and a workspace serves one bundle. Counts and equalities, never timings."""

import dataclasses
import gc
import weakref

import numpy as np
import pytest

import casmech
from casmech.errors import UsageError
from casmech.runtime import workspace as workspaces
from casmech.runtime.workspace import KINDS, Workspace
from tests.conftest import MODELS
from tests.integration.runtime.test_dynamics_reuse import counted


def test_a_bundle_is_immutable_and_keeps_no_run_data():
    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    casmech.analyze(functions, t_end=0.1)
    assert not hasattr(functions, "derived")
    with pytest.raises(dataclasses.FrozenInstanceError):
        functions.mode = "compiled"
    assert functions.mode == "interpreted"
    assert len(workspaces.default(functions)) > 0  # the run's data went there


@pytest.mark.parametrize("formulation", ["rp", "joint"])
def test_a_workspace_of_its_own_builds_again_and_gives_the_same_rows(monkeypatch, formulation):
    """The default workspace makes a repeated run create no integrator; a run given a new
    workspace creates its own, and the rows are the same bit for bit."""
    functions = casmech.compile(casmech.load(MODELS / "bricard.yaml"))
    made = counted(monkeypatch)
    settings = {"formulation": formulation, "method": "bdf", "t_end": 0.2}  # IDAS: counted
    first = casmech.analyze(functions, **settings)
    count = len(made)
    again = casmech.analyze(functions, **settings)
    assert len(made) == count >= 1
    own = Workspace(functions)
    fresh = casmech.analyze(functions, **settings, workspace=own)
    assert len(made) == 2 * count and len(own) > 0
    for result in (again, fresh):
        np.testing.assert_array_equal(result.q, first.q)
        np.testing.assert_array_equal(result.lam, first.lam)


def test_a_workspace_serves_one_bundle():
    model = casmech.load(MODELS / "double_pendulum.yaml")
    one, other = casmech.compile(model), casmech.compile(model)
    own = Workspace(one)
    casmech.analyze(one, t_end=0.1, workspace=own)
    with pytest.raises(UsageError, match="another bundle"):
        casmech.analyze(other, t_end=0.1, workspace=own)
    unbound = Workspace()  # bound on first use
    casmech.analyze(other, t_end=0.1, workspace=unbound)
    with pytest.raises(UsageError, match="another bundle"):
        casmech.analyze(one, t_end=0.1, workspace=unbound)


def test_the_default_workspace_goes_with_its_bundle():
    """No entry holds the bundle: dropping the bundle frees it and its workspace."""
    functions = casmech.compile(casmech.load(MODELS / "four_bar.yaml"))
    for analysis in ("dynamics", "kinematics", "statics"):
        try:
            casmech.analyze(functions, analysis, t_end=0.1)
        except casmech.AnalysisError:
            pass  # (statics of a driven four-bar has no equilibrium: its entries still made)
    casmech.results_table(functions, casmech.analyze(functions, t_end=0.1))
    bundle, kept = weakref.ref(functions), weakref.ref(workspaces.default(functions))
    del functions
    gc.collect()
    assert bundle() is None and kept() is None


def test_every_kind_is_bounded():
    """Many grids, tolerances and starts: no kind holds more entries than KINDS allows."""
    functions = casmech.compile(casmech.load(MODELS / "bricard.yaml"))
    own = Workspace(functions)
    for k in range(12):
        for formulation in ("rp", "joint"):
            casmech.analyze(functions, formulation=formulation, t_end=0.05 + 0.01 * k,
                            rtol=1e-8 * (1 + k), workspace=own)
    sizes = {kind: len(own.store(kind)) for kind in KINDS}
    assert all(size <= KINDS[kind] for kind, size in sizes.items()), sizes
    assert sizes["dae_integrators"] == KINDS["dae_integrators"]  # (it was filled)


def test_kinds_are_a_closed_list():
    with pytest.raises(KeyError, match="no workspace entry kind"):
        Workspace().store("anything")


@pytest.mark.parametrize("given", ["loaded", "path"])
def test_an_analysis_of_anything_but_a_bundle_is_a_usage_error(given):
    """casmech.analyze(casmech.load(path)) forgets the compile step: a UsageError that says
    so, not a TypeError from inside the workspace."""
    path = MODELS / "double_pendulum.yaml"
    value = casmech.load(path) if given == "loaded" else path
    with pytest.raises(UsageError, match="system functions, not (ResolvedModel|PosixPath)"):
        casmech.analyze(value, t_end=0.1)
    if given == "loaded":
        with pytest.raises(UsageError, match=r"casmech.compile\(model\)"):
            casmech.analyze(value)
