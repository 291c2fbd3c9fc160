"""Runs of a tree above solver.compile.mapped_bodies (lowered here to small trees) take the
mapped joint system (formulations/mapped_system.py, its kernels compiled through the test
session's cache) and agree with the unrolled build's runs to integrator level, through the
results table (the results rows and relative poses are the mapped ones too); a model the
kernels do not cover runs the unrolled build whatever the option says."""

import numpy as np
import pytest

import casmech
from casmech.core.options import DynamicsSolver, JointCompile
from casmech.formulations import mapped_system
from casmech.runtime.joint_dynamics import joint_system
from tests.conftest import MODELS, Table
from tests.unit.formulations.test_mapped_tree import BRANCHED, spherical_chain

MAPPED = DynamicsSolver(compile=JointCompile(mapped_bodies=0))


def _table(text: str, solver: str = "", **options) -> Table:
    text = text.replace("analysis: {type: dynamics,",
                        "analysis: {type: dynamics, formulation: joint, rtol: 1.0e-10, "
                        f"atol: 1.0e-12,{solver}")
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions, **options)
    return Table(*casmech.results_table(functions, result))


@pytest.mark.parametrize("text", [spherical_chain(4), BRANCHED], ids=["chain", "branched"])
def test_a_mapped_run_agrees_with_the_unrolled_one(text, quick_builds, monkeypatch):
    built = []
    monkeypatch.setattr(mapped_system, "build",
                        lambda *args, build=mapped_system.build: built.append(1) or build(*args))
    functions = casmech.compile(casmech.loads(text))
    system = joint_system(functions, MAPPED)
    assert system.dynamics.is_a("MXFunction")
    assert {f.class_name() for f in system.dynamics.find_functions()} == {"External"}
    assert joint_system(functions).dynamics.is_a("SXFunction")  # the default: 128 bodies
    mapped = _table(text, " solver: {compile: {mapped_bodies: 0}},")
    assert len(built) == 2  # the option read from the file's solver settings
    unrolled = _table(text)
    assert len(built) == 2 and len(unrolled.names) > 20
    for name in unrolled.names[1:]:
        scale = max(1.0, np.max(np.abs(unrolled[name])))
        # the same equations, integrated at rtol 1e-10: the runs' own error
        np.testing.assert_allclose(mapped[name], unrolled[name], rtol=0, atol=1e-7 * scale,
                                   err_msg=name)


def test_bdf_differentiates_through_the_kernels(quick_builds):
    """BDF's Newton iteration takes the mapped ODE's Jacobian by forward sweeps through the
    compiled kernels' derivatives (a block of four joints and a single one): the same motion
    as Adams."""
    text = spherical_chain(5)
    solver = " solver: {compile: {mapped_bodies: 0}},"
    adams, bdf = (_table(text, solver, method=method) for method in ("adams", "bdf"))
    for name in ("bar3.x", "bar3.z", "bar2.vx"):
        # two integrators at rtol 1e-10: their errors
        np.testing.assert_allclose(bdf[name], adams[name], rtol=0, atol=1e-6, err_msg=name)


@pytest.mark.parametrize("model", ["bushing_mount.yaml", "four_bar.yaml"])
def test_a_tree_the_kernels_do_not_cover_runs_unrolled(model):
    functions = casmech.compile(casmech.load(MODELS / model))
    assert joint_system(functions, MAPPED).dynamics.is_a("SXFunction")


def test_without_compiled_kernels_the_tree_is_built_unrolled(monkeypatch):
    """No C compiler (or no usable cache): the unrolled SX, which evaluates faster than the
    kernels interpreted in an MX graph, with the kernels' warning."""

    monkeypatch.setenv("CC", "no-such-compiler-cc")
    functions = casmech.compile(casmech.loads(spherical_chain(3)), "interpreted")
    with pytest.warns(UserWarning, match="built unrolled"):
        system = joint_system(functions, MAPPED)
    assert system.dynamics.is_a("SXFunction")


def test_method_auto_keeps_adams_above_mapped_bodies(quick_builds):
    """Method auto on a tree above compile.mapped_bodies is Adams (DOP853 would run its Python
    path over the mapped MX ODE: runtime.joint_dynamics.choose_method); the same tree
    compiled under the default size rule, and the mapped one asked for dop853, run DOP853,
    the same motion."""
    text = spherical_chain(4)
    solver = " solver: {compile: {mapped_bodies: 0}},"
    runs = {}
    for label, settings, method, mode in (
            ("mapped", solver, "auto", "auto"), ("unrolled", "", "auto", "compiled"),
            ("asked", solver, "dop853", "auto")):
        functions = casmech.compile(casmech.loads(text.replace(
            "analysis: {type: dynamics,", "analysis: {type: dynamics, formulation: joint, "
            f"rtol: 1.0e-10, atol: 1.0e-12,{settings}")), mode)
        runs[label] = casmech.analyze(functions, method=method)
    assert [runs[k].metadata["method"] for k in ("mapped", "unrolled", "asked")] == \
        ["adams", "dop853", "dop853"]
    for label in ("unrolled", "asked"):
        # two integrators at rtol 1e-10 over the same motion: their errors
        np.testing.assert_allclose(runs[label].q, runs["mapped"].q, rtol=0, atol=1e-7)
