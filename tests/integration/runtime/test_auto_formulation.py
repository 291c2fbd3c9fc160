"""formulation: auto (runtime/auto_formulation.py): joint coordinates for trees and loops,
rp after a joint run that failed or passed a singular pose, and where joint coordinates
would not pay."""

import numpy as np
import pytest

import casmech
from casmech.errors import AnalysisError, FailureContext, Interrupted
from casmech.runtime import auto_formulation
from casmech.runtime.joint_dynamics import joint_system, tree_of
from casmech.runtime.results import Result
from tests.conftest import MODELS, ROOT
from tests.helpers.reference_data import read_analytic
from tests.helpers.statics_models import HANGING_FOUR_BAR
from tests.validation.runtime.test_validation_iftomm import A02, a02_b0_error

FOUR_BAR = ROOT / "benchmarks" / "models" / "four_bar.yaml"


def test_loops_run_in_joint_coordinates_and_agree_with_rp():
    """Bricard's mechanism (a redundant loop, no singular pose in its motion) runs the joint
    DAE under auto, and moves as the r-p DAE does."""
    functions = casmech.compile(casmech.load(MODELS / "bricard.yaml"))
    auto = casmech.analyze(functions, t_end=0.3, rtol=1e-10, atol=1e-12)
    rp = casmech.analyze(functions, formulation="rp", t_end=0.3, rtol=1e-10, atol=1e-12)
    assert auto.metadata["formulation"] == "joint"
    assert "formulation_fallback" not in auto.metadata
    # positions of 1 m links at rtol 1e-10: both within ~1e-9 of the exact motion
    np.testing.assert_allclose(auto.q, rp.q, rtol=0, atol=1e-7)
@pytest.mark.slow  # long validation: `python -m pytest -m slow` runs it
def test_a_singular_pose_sends_the_run_to_rp_and_it_matches_the_exact_motion():
    """IFToMM A02 passes flat poses from t = 0.71 s on: the joint DAE goes through them
    drifting off the exact motion without failing, the singular-pose check sees them, and
    the run is redone in rp, whose B0 follows the exact parallelogram reduction (the
    benchmark's reference)."""
    exact = read_analytic("A02_Nfourbar_N2_0-10s.csv")
    functions = casmech.compile(casmech.load(A02))
    result = casmech.analyze(functions, t_end=3.0, rtol=1e-8, atol=1e-10)
    assert result.metadata["formulation"] == "rp"
    assert "singular pose at t = 0.7" in result.metadata["formulation_fallback"]
    n = len(result.times)
    error, _ = a02_b0_error(functions, result, {k: v[:n] for k, v in exact.items()})
    assert error <= 1e-6  # the rp run's accuracy at rtol 1e-8 (2.4e-8 m measured)
    # and the joint DAE alone was off (9e-6 m measured): what the check protects against
    joint = casmech.analyze(functions, formulation="joint", method="bdf", t_end=3.0, rtol=1e-8,
                            atol=1e-10)
    joint_error, _ = a02_b0_error(functions, joint, {k: v[:n] for k, v in exact.items()})
    assert joint_error > 10 * error


@pytest.mark.parametrize("path, why", [
    (MODELS / "validation" / "distance_case01.yaml", "a floating body closed by cut rows"),
    (MODELS / "ocp_arm3d.yaml", "a payload held by six basic constraints")])
def test_loops_through_a_floating_body_run_rp(path, why):
    functions = casmech.compile(casmech.load(path))
    result = casmech.analyze(functions, t_end=0.05)
    assert result.metadata["formulation"] == "rp", why


@pytest.mark.parametrize("method", ["dop853", "adams"])
def test_a_method_of_joint_coordinates_on_a_floating_loop_is_a_located_error(method):
    """auto runs a loop through a floating body in rp, which IDAS's BDF integrates: the file's
    method is E409 at its own line before anything runs (`casmech check` reports it too, by
    the same analysis_settings); the caller's, a UsageError saying the same."""
    from casmech.api import analysis_settings
    from casmech.errors import ModelError, UsageError

    path = MODELS / "validation" / "distance_case01.yaml"
    text = path.read_text().replace("  atol: 1.0e-12\n", f"  atol: 1.0e-12\n  method: {method}\n")
    line = text.splitlines().index(f"  method: {method}") + 1
    functions = casmech.compile(casmech.loads(text, "distance.yaml"), "interpreted")
    with pytest.raises(ModelError) as raised:
        casmech.analyze(functions, t_end=0.05)
    [diagnostic] = raised.value.diagnostics
    assert (diagnostic.code, diagnostic.path, diagnostic.got) == ("E409", "analysis.method",
                                                                   method)
    assert diagnostic.format().startswith(
        f"distance.yaml:{line}:11: error[E409] analysis.method: method {method} integrates "
        "joint coordinates of a tree")
    assert "formulation auto runs this model in rp" in diagnostic.message
    assert "body 'pendulum' floats" in diagnostic.message
    assert "method: bdf" in diagnostic.hint and "formulation: joint" in diagnostic.hint
    assert analysis_settings(functions, method="bdf").options.method == "bdf"  # a caller's
    plain = casmech.compile(casmech.load(path), "interpreted")
    with pytest.raises(UsageError, match=rf"error\[E409\] method = {method}: method {method} "
                       "integrates joint coordinates of a tree"):
        casmech.analyze(plain, t_end=0.05, method=method)
    if method == "adams":  # a tree's method: on loops in any formulation IDAS's BDF would run
        with pytest.raises(UsageError, match="this model has loops"):
            casmech.analyze(plain, t_end=0.05, method=method, formulation="joint")
        return
    # formulation joint runs dop853 (the body's free joint among the tree's coordinates)
    joint = casmech.analyze(plain, t_end=0.05, method=method, formulation="joint")
    assert joint.metadata["formulation"] == "joint"


def test_a_callers_method_of_joint_coordinates_with_rp_is_an_error():
    """The schema refuses `method: dop853` beside `formulation: rp` in a file (E409); the
    caller's pair says the same, instead of running IDAS."""
    from casmech.errors import UsageError

    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"), "interpreted")
    with pytest.raises(UsageError, match=r"method dop853 integrates joint coordinates of a "
                       r"tree or the projected ODE of its loops; the rp and romega DAEs are "
                       r"integrated by IDAS's BDF method"):
        casmech.analyze(functions, t_end=0.05, formulation="rp", method="dop853")
    with pytest.raises(UsageError, match=r"method = adams: .* \(a DAE stabilization asked "
                       r"for makes formulation auto run rp\)"):
        casmech.analyze(functions, t_end=0.05, stabilization="ggl", method="adams")


def test_a_failed_joint_run_is_redone_in_rp_and_an_interrupt_is_not():
    functions = casmech.compile(casmech.load(FOUR_BAR))
    tree = tree_of(functions)
    done = Result("dynamics", {"formulation": "rp"})

    def failing():
        raise AnalysisError(FailureContext(0.25, "the integrator failed", [], ""))

    def other(formulation):
        assert formulation == "rp"
        return done

    result = auto_formulation.run(functions, tree, "auto", 11, failing, other)
    assert result is done
    assert "the joint DAE failed" in result.metadata["formulation_fallback"]
    # asked for explicitly, joint coordinates are not replaced
    with pytest.raises(AnalysisError):
        auto_formulation.run(functions, tree, "joint", 11, failing, other)

    def interrupted():
        raise Interrupted(2)  # SIGINT

    with pytest.raises(Interrupted):
        auto_formulation.run(functions, tree, "auto", 11, interrupted, other)


def test_adams_on_loops_is_a_located_error():
    """Adams integrates a tree's ODE; loops' DAE in joint coordinates goes to IDAS, whose only
    method is BDF: the file's `method: adams` on a four-bar (no floating body) is E409 at its
    line, the caller's (under auto or joint) a UsageError, instead of a BDF run the metadata
    calls bdf; dop853 and bdf, the methods the hint names, run."""
    from casmech.errors import ModelError, UsageError

    text = FOUR_BAR.read_text().replace("  atol: 1.0e-10\n", "  atol: 1.0e-10\n  method: adams\n")
    line = text.splitlines().index("  method: adams") + 1
    functions = casmech.compile(casmech.loads(text, "four_bar.yaml"), "interpreted")
    with pytest.raises(ModelError) as raised:
        casmech.analyze(functions, t_end=0.05)
    [diagnostic] = raised.value.diagnostics
    assert diagnostic.format().startswith(
        f"four_bar.yaml:{line}:11: error[E409] analysis.method: method adams integrates joint "
        "coordinates of a tree; this model has loops, whose DAE in joint coordinates is "
        "integrated by IDAS's BDF method")
    assert "method: dop853" in diagnostic.hint and "bdf" in diagnostic.hint
    plain = casmech.compile(casmech.load(FOUR_BAR), "interpreted")
    for formulation in ("auto", "joint"):
        with pytest.raises(UsageError, match=r"error\[E409\] method = adams: .* has loops"):
            casmech.analyze(plain, t_end=0.05, method="adams", formulation=formulation)
    runs = {method: casmech.analyze(plain, t_end=0.05, method=method, formulation="joint")
            for method in ("bdf", "dop853")}
    assert {m: r.metadata["method"] for m, r in runs.items()} == {"bdf": "bdf",
                                                                  "dop853": "dop853"}
    gears = casmech.compile(casmech.load(MODELS / "gear_pair.yaml"), "interpreted")
    with pytest.raises(UsageError, match="has loops or couplings"):
        casmech.analyze(gears, t_end=0.05, method="adams")


def test_choice_table():
    """What runs first, by the facts choice() is given."""
    tree = tree_of(casmech.compile(casmech.load(FOUR_BAR)))

    def fact(value):
        return lambda: value

    assert auto_formulation.choice(tree, "auto", fact(True), fact(False)) == "joint"
    assert auto_formulation.choice(tree, "auto", fact(False), fact(False)) == "rp"  # unexamined
    assert auto_formulation.choice(tree, "auto", fact(True), fact(True)) == "rp"  # not compiled
    assert auto_formulation.choice(tree, "romega", fact(True), fact(False)) == "romega"
    # dop853 asked for: joint coordinates wherever they apply (its projected loop ODE)
    assert auto_formulation.choice(tree, "auto", fact(False), fact(True), "dop853") == "joint"
    # (adams asked for on loops never gets here: method_problem refuses it first, below)


def test_a_tree_is_not_examined_for_its_choice():
    """A tree runs in joint coordinates whatever its rows: choice() asks neither fact."""
    tree = tree_of(casmech.compile(casmech.load(MODELS / "double_pendulum.yaml")))
    assert tree.is_tree

    def never():
        raise AssertionError("asked")

    assert auto_formulation.choice(tree, "auto", never, never) == "joint"


@pytest.mark.slow  # long validation: `python -m pytest -m slow` runs it
def test_compiled_loops_equal_interpreted(tmp_path, monkeypatch):
    """The loops' DAE and its Jacobian compiled (a compiled bundle) give the interpreted
    run's rows (the same arithmetic; roundoff at most). Method bdf named: under auto the
    compiled bundle runs the loops' projected ODE on DOP853, the interpreted one the DAE."""
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path))
    model = casmech.load(FOUR_BAR)
    bundles = [casmech.compile(model, mode=mode) for mode in ("interpreted", "compiled")]
    runs = [casmech.analyze(f, t_end=0.2, method="bdf") for f in bundles]
    assert [r.metadata["formulation"] for r in runs] == ["joint", "joint"]
    assert joint_system(bundles[1]).dynamics.class_name() == "External"
    # IDAS takes the same steps when both evaluate the same expressions
    for state in ("q", "q_dot", "lam"):
        np.testing.assert_allclose(getattr(runs[1], state), getattr(runs[0], state), rtol=0,
                                   atol=1e-9 * max(1.0, np.max(np.abs(getattr(runs[0], state)))))


def test_a_planar_loop_of_revolutes_masks_the_rows_its_tree_cannot_violate():
    """A hanging four-bar of revolutes in 3D: the cut revolute's out-of-plane rows (two DP1
    and one position row) have no velocity Jacobian in the tree's coordinates; they are masked
    and the results table equals the r-p DAE's (the same minimum-norm reactions)."""
    head, _, _ = HANGING_FOUR_BAR.rpartition("\nanalysis:")
    functions = casmech.compile(casmech.loads(head + "\nanalysis: {type: dynamics}\n"))
    runs = {form: casmech.analyze(functions, formulation=form, t_end=0.5, rtol=1e-10,
                                  atol=1e-12) for form in ("auto", "rp")}
    assert runs["auto"].metadata["formulation"] == "joint"
    assert runs["auto"].metadata["dropped_rows"] == 3
    names, auto = casmech.results_table(functions, runs["auto"])
    _, rp = casmech.results_table(functions, runs["rp"])
    scale = np.maximum(1.0, np.max(np.abs(rp), axis=0))
    # both within ~1e-9 of the exact motion at rtol 1e-10; reactions of ~20 N to 1e-6
    np.testing.assert_allclose(np.asarray(auto) / scale, np.asarray(rp) / scale, rtol=0,
                               atol=1e-6, err_msg=str(names))


def test_an_explicit_stabilization_means_rp():
    """api.analysis_settings, the one place of the rule: formulation auto with a stabilization
    asked for (by the caller, even ggl, or a file's other than the default) resolves to rp;
    without one auto stays auto, and an explicit formulation is kept."""
    from casmech.api import analysis_settings

    functions = casmech.compile(casmech.load(FOUR_BAR))
    formulation = lambda f, **given: analysis_settings(f, **given).options.formulation  # noqa: E731
    assert formulation(functions) == "auto"
    assert formulation(functions, stabilization="ggl") == "rp"
    assert formulation(functions, stabilization="projection") == "rp"
    assert formulation(functions, stabilization="projection", formulation="romega") == "romega"
    text = FOUR_BAR.read_text().replace("atol: 1.0e-10",
                                        "atol: 1.0e-10\n  stabilization: projection")
    in_file = casmech.compile(casmech.loads(text))
    assert formulation(in_file) == "rp"
    assert formulation(in_file, formulation="joint") == "joint"
