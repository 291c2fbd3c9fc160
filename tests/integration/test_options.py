"""The typed options of each analysis type (casmech.core.options): set from YAML (`analysis:
{solver: ...}`), the command line (`--option KEY=VALUE`) and the API (`options=`) through the
one object, checked alike (located errors in YAML, one-line usage errors otherwise), recorded
in metadata.json and repeated by --replay; documented in docs/analyses.md (the tables are
generated: `python -m tests.options_reference`); and each family of options taking effect, by
a property independent of casmech's own numbers."""

import json
import math

import numpy as np
import pytest

import casmech
from casmech.cli import main
from casmech.core import option_values
from casmech.core.options import (
    OPTIONS,
    DynamicsOptions,
    DynamicsSolver,
    KinematicsOptions,
    StaticsOptions,
)
from casmech.errors import AnalysisError, ModelError, UsageError
from tests import options_reference
from tests.conftest import MODELS

PENDULUM = """\
casmech: 1
name: pendulum
bodies:
  - {name: bar, mass: 1, inertia: [0.1, 0.1, 0.1], position: [1, 0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 1, 0]}
analysis:
  type: dynamics
  t_end: 1.0
  output_step: 0.05
ANALYSIS"""


def pendulum(extra: str = "") -> str:
    return PENDULUM.replace("ANALYSIS", extra)


# ------------------------------------------------------------------------------ documented
def test_the_tables_of_docs_analyses_are_current():
    text = options_reference.DOC.read_text(encoding="utf-8")
    assert options_reference.regenerate(text) == text, (
        "docs/analyses.md is stale: run `python -m tests.options_reference`")
    assert sorted(options_reference.documented(text)) == sorted(options_reference.CLASSES)


@pytest.mark.parametrize("kind", sorted(OPTIONS))
def test_every_key_of_every_type_is_in_the_docs(kind):
    """Each key's last name is a row of a documented table (the nested tables are linked)."""
    text = options_reference.DOC.read_text(encoding="utf-8")
    for key in option_values.keys(OPTIONS[kind]):
        assert f"| `{key.split('.')[-1]}` |" in text, key


def test_every_field_has_a_meaning_and_its_default_is_in_range():
    """Every default passes its own check (a range that excluded a default would refuse the
    value a run uses when nothing is written)."""
    for kind in OPTIONS.values():
        for path, _ in option_values.leaves(kind):
            value = kind()
            for step in path:
                value = getattr(value, step)
            converted, problem = option_values.check_value(kind, path, value)
            assert problem is None and converted == value, path


# ----------------------------------------------------------------------------------- YAML
@pytest.mark.parametrize("solver, code, path, hint", [
    ("{max_stp: 1.0e-3}", "E101", "analysis.solver.max_stp", "did you mean 'max_step'?"),
    ("{assembly: {tolerence: 1.0e-10}}", "E101", "analysis.solver.assembly.tolerence",
     "did you mean 'tolerance'?"),
    ("{penalty: 1.0e6}", "E101", "analysis.solver.penalty",
     "did you mean 'solver.fallback.penalty'?"),
    ("{formulation: rp}", "E101", "analysis.solver.formulation", "a key of analysis: itself"),
    ("{max_steps: 2.5}", "E102", "analysis.solver.max_steps", None),
    ("{max_step: fast}", "E102", "analysis.solver.max_step", None),
    ("{assembly: 3}", "E102", "analysis.solver.assembly", None),
    ("{chunk: 0}", "E409", "analysis.solver.chunk", None),
    ("{max_step: -1.0e-3}", "E409", "analysis.solver.max_step", None),
    ("{singular_pose_ratio: 2}", "E409", "analysis.solver.singular_pose_ratio", None),
])
def test_a_bad_solver_block_is_a_located_error(solver, code, path, hint):
    text = pendulum(f"  solver: {solver}\n")
    with pytest.raises(ModelError) as caught:
        casmech.loads(text, file="pendulum.yaml")
    [found] = caught.value.diagnostics
    line = len(text.splitlines())  # the solver line is the last one
    assert (found.code, found.path) == (code, path)
    assert found.source.file == "pendulum.yaml" and found.source.line == line
    assert found.expected  # what would have been right
    if hint:
        assert hint in (found.hint or "")


def test_the_solver_block_is_checked_against_the_type():
    """statics has max_iterations, dynamics has not: the same block is right for one type."""
    block = "  solver: {max_iterations: 500}\n"
    statics = casmech.loads(pendulum(block).replace("type: dynamics", "type: statics"))
    assert statics.analysis.options.solver.max_iterations == 500
    with pytest.raises(ModelError, match=r"E101\] analysis.solver.max_iterations"):
        casmech.loads(pendulum(block))


# ------------------------------------------------------------------ one object, three ways
def test_yaml_cli_and_api_set_the_same_options(tmp_path, capsys):
    """max_step and an assembly tolerance from the file, from --option and from the API (a
    mapping and a dataclass): the same typed options, the same rows bit for bit."""
    written = pendulum("  formulation: rp\n  solver: {max_step: 0.002, initial_step: 1.0e-5, "
                       "assembly: {tolerance: 1.0e-11}}\n")
    plain = pendulum("  formulation: rp\n")
    from_file = casmech.compile(casmech.loads(written))
    functions = casmech.compile(casmech.loads(plain))
    mapping = {"max_step": 0.002, "solver.initial_step": "1e-5", "assembly.tolerance": 1e-11}
    solver = DynamicsSolver(max_step=0.002, initial_step=1e-5,
                            assembly=DynamicsSolver().assembly.__class__(tolerance=1e-11))
    typed = DynamicsOptions(formulation="rp", solver=solver)
    assert from_file.ir.analysis.options == typed
    assert casmech.api.analysis_settings(functions, options=mapping).options == typed
    runs = [casmech.analyze(from_file), casmech.analyze(functions, options=mapping),
            casmech.analyze(functions, options=typed)]
    (tmp_path / "plain.yaml").write_text(plain)
    assert main(["run", str(tmp_path / "plain.yaml"), "--out", str(tmp_path / "out"),
                 "--option", "max_step=0.002", "--option", "initial_step=1e-5",
                 "--option", "solver.assembly.tolerance=1e-11"]) == 0
    from casmech.io.frames import load_results

    table = load_results(tmp_path / "out")
    for run in runs[1:]:
        np.testing.assert_array_equal(run.q, runs[0].q)
    expected = casmech.results_table(from_file, runs[0])[1][:, 1:]
    # the CSV holds the shortest text that reads back to the same double
    np.testing.assert_array_equal(table.to_numpy(), expected)
    record = json.loads((tmp_path / "out" / "metadata.json").read_text())
    assert record["analysis"]["solver"]["max_step"] == 0.002
    assert record["analysis"]["solver"]["assembly"]["tolerance"] == 1e-11
    assert record["options"]["option"] == ["max_step=0.002", "initial_step=1e-5",
                                           "solver.assembly.tolerance=1e-11"]


def test_replay_repeats_the_options(tmp_path):
    (tmp_path / "p.yaml").write_text(pendulum())
    assert main(["run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "a"),
                 "--option", "max_step=0.003"]) == 0
    assert main(["run", "--replay", str(tmp_path / "a" / "metadata.json")]) == 0
    replayed = json.loads((tmp_path / "a_replay" / "metadata.json").read_text())
    assert replayed["analysis"]["solver"]["max_step"] == 0.003
    assert replayed["options"]["option"] == ["max_step=0.003"]
    assert (tmp_path / "a_replay" / "results.csv").read_text() == \
        (tmp_path / "a" / "results.csv").read_text()


@pytest.mark.parametrize("args, message", [
    (["--option", "max_stp=1e-3"], "did you mean 'max_step'?"),
    (["--option", "chunk=0"], "dynamics option solver.chunk: out of range; expected x >= 1"),
    (["--option", "max_steps=many"], "expected an integer"),
    (["--option", "max_step"], "--option expects KEY=VALUE"),
    (["--option", "max_step=1", "--option", "max_step=2"], "given twice"),
    (["--analysis", "statics", "--option", "max_step=1e-3"],
     "statics option max_step: unknown option"),
])
def test_a_bad_option_is_a_one_line_usage_error(tmp_path, capsys, args, message):
    (tmp_path / "p.yaml").write_text(pendulum())
    assert main(["run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "o"), *args]) == 2
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1 and message in error, error
    assert not (tmp_path / "o").exists()  # refused before anything is written


def test_the_api_refuses_what_does_not_fit():
    functions = casmech.compile(casmech.loads(pendulum()))
    with pytest.raises(UsageError, match="did you mean 'max_steps'"):
        casmech.analyze(functions, options={"max_stps": 10})
    with pytest.raises(UsageError, match="a DynamicsOptions"):
        casmech.analyze(functions, options=KinematicsOptions())
    with pytest.raises(UsageError, match="a StaticsOptions .or a mapping., not a Dynamics"):
        casmech.analyze(functions, "statics", options=DynamicsOptions())


def test_another_type_takes_the_keys_the_file_wrote_that_it_has():
    """A statics model run as dynamics keeps its assembly tolerance and its formulation,
    drops its statics-only keys; run as statics again, it has them all."""
    text = pendulum("  formulation: rp\n  solver: {max_iterations: 7, assembly: "
                    "{tolerance: 1.0e-10}}\n").replace("type: dynamics", "type: statics")
    functions = casmech.compile(casmech.loads(text))
    dynamics = casmech.api.analysis_settings(functions, "dynamics").options
    assert dynamics == DynamicsOptions(formulation="rp", solver=DynamicsSolver(
        assembly=DynamicsSolver().assembly.__class__(tolerance=1e-10)))
    statics = casmech.api.analysis_settings(functions).options
    assert isinstance(statics, StaticsOptions) and statics.solver.max_iterations == 7


# --------------------------------------------------------------------------- in effect
@pytest.mark.parametrize("formulation, steps", [("rp", "idas_steps"), ("joint", "steps")])
def test_max_step_bounds_the_step_count_from_below(formulation, steps):
    """A step of at most h over 1 s takes at least 1 / h steps (SUNDIALS' hmax), where the
    integrator's own choice takes far fewer on a pendulum."""
    functions = casmech.compile(casmech.loads(pendulum()))
    tight = {"rtol": 1e-10, "atol": 1e-12, "formulation": formulation}
    free = casmech.analyze(functions, **tight)
    capped = casmech.analyze(functions, **tight, options={"max_step": 1e-3})
    assert free.metadata[steps] < 500 <= 1000 <= capped.metadata[steps]
    # the same motion, each within its rtol 1e-10 of the exact one over 1 s (measured 2e-8
    # apart in joint coordinates: Adams' global error; 3e-10 by IDAS)
    np.testing.assert_allclose(capped.q, free.q, rtol=0, atol=1e-7)


@pytest.mark.parametrize("method, budget", [("adams", 5), ("dop853", 1)])
def test_max_steps_is_the_integrators_budget_per_output_interval(method, budget):
    """Five Adams steps, or one DOP853 step, cannot cross 0.05 s of a pendulum at rtol 1e-8
    from the start (their first steps are short): the joint run fails in its first output
    interval, which the error names."""
    functions = casmech.compile(casmech.loads(pendulum()))
    with pytest.raises(AnalysisError, match=r"failed between t = 0 and 0\.05") as caught:
        casmech.analyze(functions, formulation="joint", method=method,
                        options={"max_steps": budget})
    assert len(caught.value.partial) == 1  # the start only


def test_assembly_iterations_and_tolerance():
    """A driver at pi/2 at t = 0 turns the pendulum from the file's pose by Newton steps
    (continuation in steps of at most 0.5 rad): one iteration is not enough (the error says
    so); a looser tolerance stops earlier, within it."""
    text = pendulum().replace("axis: [0, 1, 0]}", "axis: [0, 1, 0], driver: {angle: pi/2}}")
    functions = casmech.compile(casmech.loads(text))
    with pytest.raises(AnalysisError, match="did not converge .* in 1 Newton iterations"):
        casmech.analyze(functions, "assembly", options={"assembly.max_iterations": 1})
    loose = casmech.analyze(functions, "assembly", options={"assembly.tolerance": 1e-4})
    tight = casmech.analyze(functions, "assembly")
    phi = functions.vector("phi", 0.0, loose.q[0])
    assert np.max(np.abs(phi)) <= 1e-4
    np.testing.assert_allclose(loose.q, tight.q, rtol=0, atol=1e-3)


def test_statics_iterations_and_force_tolerance():
    """A pendulum released horizontally hangs down after enough pseudo-time steps; with one
    step statics reports no equilibrium; a looser force tolerance ends sooner, its residual
    within it (relative to the weight, 9.81 N)."""
    text = pendulum().replace("type: dynamics", "type: statics")
    functions = casmech.compile(casmech.loads(text))
    with pytest.raises(AnalysisError, match="no static equilibrium found in 1 iterations"):
        casmech.analyze(functions, options={"max_iterations": 1})
    tight = casmech.analyze(functions)
    loose = casmech.analyze(functions, options={"force_tolerance": 1e-3})
    assert loose.metadata["iterations"] <= tight.metadata["iterations"]
    assert loose.metadata["residual_norm"] <= 1e-3 * 9.81
    # hanging straight down: x = 0, z = -1 (the exact equilibrium)
    np.testing.assert_allclose(tight.q[0, :3], [0, 0, -1], rtol=0, atol=1e-9)


def test_kinematics_rows_all_by_the_per_row_code():
    """pivot_ratio 1 rejects every mapped row (min/max |R_kk| <= 1): every row is done by the
    per-row NumPy code, the same rows as the mapped step's to its Newton tolerance."""
    functions = casmech.compile(casmech.load(MODELS / "four_bar.yaml"))
    mapped = casmech.analyze(functions, "kinematics", t_end=0.2, output_step=0.01)
    per_row = casmech.analyze(functions, "kinematics", t_end=0.2, output_step=0.01,
                              options={"pivot_ratio": 1.0})
    assert mapped.metadata["per_row_rows"] == 0
    assert per_row.metadata["per_row_rows"] == len(per_row)
    # two Newton solutions to |Phi| <= 1e-12 with O(1) Jacobians
    np.testing.assert_allclose(per_row.q, mapped.q, rtol=0, atol=1e-10)


def test_event_iterations_bound_the_location():
    """A falling body's stop event at z = 0 from 1 m: exact at sqrt(2 / g); two Illinois
    steps leave it less accurate than the default hundred."""
    text = pendulum().replace(
        "joints:\n  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], "
        "axis: [0, 1, 0]}\n", "joints: []\n").replace("position: [1, 0, 0]", "position: [0, 0, 1]")
    text += "events:\n  - {name: ground, when: bar.z, direction: falling, action: stop}\n"
    functions = casmech.compile(casmech.loads(text))
    exact = math.sqrt(2 / 9.81)
    errors = [abs(casmech.analyze(functions, options=options).events[0].t - exact)
              for options in ({"event_iterations": 2}, None)]
    assert errors[1] < 1e-8 < errors[0]  # measured errors 1e-12 and 1e-4


# ------------------------------------------------------------------ what stayed a constant
# The module-level numbers left in runtime/, formulations/, numerics/ and equations/ and why
# they are no options: sizes that bound memory or batch work, roundoff floors, mathematical
# facts, the structure of built (and compiled) code, the command line's signal count.
CONSTANTS = {
    "formulations/mapped_tree.py CONSTANTS": "the size of a body's data in the tree kernels "
                                             "(structure)",
    "formulations/mapped_tree.py BLOCK": "the joints of a chain one block kernel covers "
                                         "(structure: the compiled kernels' libraries)",
    "formulations/mapped_rows.py POSE_CONSTANTS": "the size of a joint's pose data in the tree "
                                                  "kernels (structure)",
    "formulations/mapped_rows.py MAX_ROWS": "the most rows of a tree joint (structure: the "
                                            "multipliers' compiled kernels)",
    "runtime/assembly.py MAX_CONTINUATION": "continuation steps: a bound on the time to fail",
    "runtime/buffers.py BLOCK": "columns per mapped call (batch work)",
    "runtime/buffers.py MAP_ENTRIES": "numbers per mapped call (map construction time)",
    "runtime/buffers.py KEPT_MAPS": "maps kept per call (memory)",
    "runtime/events.py ULPS": "the narrowest bracket, a roundoff floor",
    "runtime/stiffness.py STABLE_REAL": "a property of DOP853's tableau (its stability "
                                        "function on the real axis)",
    "runtime/dop853.py HERMITE_BELOW": "where an interpolant's error estimate is trusted "
                                       "(a fraction of the tolerance a step is held to)",
    "runtime/nonfinite.py ONE_ARRAY": "rows checked in one NumPy call (call overhead, memory)",
    "runtime/nonfinite.py PIECE": "the most entries one sum of squares takes (OpenBLAS threads "
                                  "longer dot products; a bound on a check, not a setting)",
    "runtime/friction.py SLACK": "a holding force's roundoff past its static limit",
    "runtime/friction.py STILL": "a rate at rest in the start state, a roundoff floor",
    "runtime/friction.py SWITCHES": "friction switches before a Zeno cascade ends a run",
    "runtime/load_checks.py LOADS": "a roundoff floor of solved friction loads' residual (a "
    "check at a segment's start and rows, not a stop of an iteration)",
    "equations/friction_load.py NEWTON_STEPS": "Newton steps unrolled on coupled friction "
    "loads (structure: quadratic from their one-joint roots; checked by LOADS)",
    "runtime/contact_friction.py STILL": "a slip at rest in the start state, a roundoff floor",
    "runtime/contact_friction.py SLIP_STOP": "a slip speed that stopped: tried stuck (settle "
                                             "releases it if it cannot be)",
    "runtime/contact_friction.py TOUCH": "a gap touching at a segment's start, a roundoff "
                                         "floor",
    "runtime/contact_friction.py OPENING": "a stuck point's load at which its contact opened, "
                                           "a roundoff floor",
    "runtime/contact_friction.py CLOSING": "a column of the points' state (structure)",
    "runtime/contact_friction.py ROWS": "the rows of the points' state (structure)",
    "runtime/contact_friction.py UNLOADED": "a roundoff floor of a point's share of a load",
    "runtime/contact_friction.py GAP": "a column of the points' state (structure)",
    "runtime/contact_friction.py NORMAL_FORCE": "a column of the points' state (structure)",
    "runtime/interrupts.py ABANDON": "the third signal ends casmech run (the CLI's contract)",
    "runtime/kinematics.py BLOCK_SECONDS": "a mapped block's wall time (the rows are the same)",
    "runtime/nonfinite.py OVERFLOWING": "a magnitude that overflows in the next product",
    "runtime/nonfinite.py PROBES": "where a failed interval's elements are evaluated (a "
                                   "diagnosis, not a solver setting)",
    "runtime/projected_rk4.py NONFINITE_REFINEMENT": "the one refinement before a non-finite "
                                                     "try is an error (a bound on the time to "
                                                     "fail)",
    "runtime/projected_rk4.py ORDER": "the classical Runge-Kutta method's order",
    "runtime/functional_ode.py DIRECT_STATES": "which form of the same ODE CVODES gets "
                                               "(the integrator's creation time)",
    "runtime/singular_poses.py MAX_ENTRIES": "dense Jacobians held at once (memory)",
    "runtime/singular_poses.py COMPILED_ROWS": "the log-determinant's C and gcc's time "
                                               "(build cost)",
    "runtime/solver_messages.py MAX_LINES": "solver lines kept in metadata (size)",
    "formulations/joint_system.py ROW_NORM_FLOOR": "a roundoff floor compiled into libraries",
    "formulations/loop_ode.py POSITION_ITERATIONS": "the projection's Gauss-Newton steps, "
    "unrolled into its graph and compiled (structure; enough for the loosest rtol's drift)",
    "formulations/loop_ode.py FLUSH": "a floor against subnormal numbers compiled into the "
    "projection (far below any tolerance; its square a normal number)",
    "formulations/joint_system.py IDENTITY_STATES": "which Jacobian graph a tree's build makes",
    "formulations/prescribed.py ITERATIONS": "chord steps compiled into the library's step",
    "formulations/prescribed.py CHUNK": "the inner map of the step (batch work)",
    "formulations/residuals.py UNROLLED_INSTRUCTIONS": "which residual code is built",
    "numerics/element_sums.py DROPPED": "an index that is no output",
    "equations/evaluation.py MERGED_BODIES": "which code is built (common subexpressions)",
    "equations/force_kernels.py ROW": "an element's coordinates (structure)",
    "equations/row_kernels.py BODY": "a body's coordinates (structure)",
    "equations/row_kernels.py FRAME": "a body's frame (structure)",
    "equations/row_kernels.py V_BODY": "a body's velocities (structure)",
    "equations/rows.py BAKE_LIMIT": "which kernels are built (structure)",
    "numerics/instances.py MAX_DIRECTIONS": "forward directions built (structure)",
    **{f"numerics/dop853_tableau.py {name}": "DOP853's method and controller, scipy's (a test "
       "holds them equal): the algorithm, not a setting"
       for name in ("N_STAGES", "N_STAGES_EXTENDED", "INTERPOLATOR_POWER", "SAFETY",
                    "MIN_FACTOR", "MAX_FACTOR", "ERROR_ORDER")},
}


def module_numbers() -> set[str]:
    """'path NAME' of every module-level UPPER_CASE name bound to a number in the packages
    whose solver settings are options."""
    import ast

    source = MODELS.parent / "src" / "casmech"
    found = set()
    for package in ("runtime", "formulations", "numerics", "equations"):
        for path in sorted((source / package).rglob("*.py")):
            for node in ast.parse(path.read_text()).body:
                if not isinstance(node, ast.Assign | ast.AnnAssign):
                    continue
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                values = node.value.elts if isinstance(node.value, ast.Tuple) else [node.value]
                names = [n for t in targets for n in (t.elts if isinstance(t, ast.Tuple)
                                                      else [t])]
                for name, value in zip(names, values * len(names), strict=False):
                    value = value.operand if isinstance(value, ast.UnaryOp) else value
                    if (isinstance(name, ast.Name) and name.id.lstrip("_").isupper()
                            and isinstance(value, ast.Constant)
                            and type(value.value) in (int, float)):
                        found.add(f"{path.relative_to(source).as_posix()} {name.id}")
    return found


def test_the_numbers_left_as_constants_are_listed_with_a_reason():
    """A solver setting added as a module constant fails here: make it a field of its
    analysis's options (casmech.core.options) or list it with the reason it is none."""
    assert module_numbers() == set(CONSTANTS)
