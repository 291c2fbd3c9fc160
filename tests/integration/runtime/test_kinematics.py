"""Kinematics and inverse dynamics by the mapped prescribed step (formulations.prescribed) against
the per-row code (kinematics.state_at: Newton, velocity, acceleration and multiplier solves by
numpy.linalg.lstsq), on every gallery model with such an analysis and a redundant one."""

import re

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.core.options import Assembly
from casmech.errors import AnalysisError
from casmech.runtime import assembly
from casmech.runtime.kinematics import output_times, state_at
from tests.conftest import MODELS, count_calls

TOLERANCE = Assembly().tolerance  # the assembly's (casmech.core.options)

PRESCRIBED = sorted(path.stem for path in MODELS.glob("*.yaml")
                    if re.search(r"^\s+type:\s*(kinematics|inverse_dynamics)\s*$",
                                 path.read_text(), re.MULTILINE))

# Bricard's 6R loop has one redundant row (IFToMM A04); one driven hinge makes it fully driven,
# so the multipliers are the minimum-norm ones.
BRICARD_DRIVEN = (MODELS / "bricard.yaml").read_text().replace(
    "at: [0, 0, 0], axis: [0, 1, 0]}", "at: [0, 0, 0], axis: [0, 1, 0],\n"
    "     driver: {angle: '0.6 * sin(2 * t)'}}").replace("type: dynamics", "type: kinematics")

SLIDER = """
casmech: 1
name: slider
gravity: [0, 0, -9.81]
bodies:
  - {name: block, mass: 1.0, inertia: [0.1, 0.1, 0.1], position: [1, 0, 0]}
joints:
  - {name: rail, type: translational, body_i: ground, body_j: block, at: [0, 0, 0], axis: [1, 0, 0]}
  - {name: tether, type: d, body_i: ground, s_i: [0, 0, 0], body_j: block, s_j: [0, 0, 0],
     f: "%s"}
analysis: {type: inverse_dynamics, t_end: 2, output_step: 0.01}
"""


def per_row(functions, t_end, step, tolerance=TOLERANCE):
    """The per-row loop kinematics ran before the mapped step: (rows, error or None)."""
    q = assembly.assemble_positions(functions)
    q_dot, q_ddot = np.zeros_like(q), np.zeros_like(q)
    rows, previous = [], 0.0
    try:
        for t in output_times(0.0, t_end, step):
            h = t - previous
            q = assembly.newton(functions, t, q + h * q_dot + 0.5 * h * h * q_ddot,
                                tolerance=tolerance)
            q, q_dot, q_ddot, lam = state_at(functions, t, q, q_dot + h * q_ddot)
            rows.append((t, q, q_dot, q_ddot, lam))
            previous = t
    except AnalysisError as error:
        return rows, error
    return rows, None


def assert_same_rows(result, rows, scale_atol):
    np.testing.assert_array_equal(result.times, [row[0] for row in rows])
    for k, name in enumerate(("q", "q_dot", "q_ddot", "lam"), start=1):
        expected = np.array([row[k] for row in rows])
        scale = max(1.0, np.max(np.abs(expected), initial=0.0))
        np.testing.assert_allclose(getattr(result, name), expected, rtol=0,
                                   atol=scale_atol * scale, err_msg=name)


# compiled mode on one model, in the slow set: building its library takes seconds
@pytest.mark.parametrize("model, mode", [(model, "interpreted") for model in PRESCRIBED]
                         + [("bricard_driven", "interpreted"),
                            pytest.param("four_bar", "compiled", marks=pytest.mark.slow)])
def test_mapped_rows_equal_the_per_row_code(model, mode):
    """The per-row code here runs Newton to |Phi| <= 1e-14 (the analysis stops at 1e-12, which
    leaves q up to ~3e-12 from the solution; the mapped step's three Newton steps reach
    roundoff), so both are the converged solution and differ by the roundoff of the solves,
    ~cond(Phi_q) eps: measured <= 5e-14 of each quantity's largest value; 1e-12 leaves margin."""
    loaded = (casmech.loads(BRICARD_DRIVEN) if model == "bricard_driven"
              else casmech.load(MODELS / f"{model}.yaml"))
    functions = casmech.compile(loaded, mode)
    if mode == "compiled":  # the library carries the step (codegen.bundle), in C; in a
        # parametric library (codegen.parametric), called by a wrapper binding the model data
        step = functions.functions["prescribed_step"]
        called = {step.instruction_MX(k).which_function().class_name()
                  for k in range(step.n_instructions()) if step.instruction_id(k) == ca.OP_CALL
                  } if step.is_a("MXFunction") else {step.class_name()}
        assert called == {"External"}
    settings = functions.ir.analysis
    t_end = min(settings.t_end, 2.0)
    result = casmech.analyze(functions, t_end=t_end)
    rows, error = per_row(functions, t_end, settings.output_step, tolerance=1e-14)
    assert error is None and result.metadata["per_row_rows"] == 0
    assert_same_rows(result, rows, 1e-12)


def test_redundant_rows_get_minimum_norm_multipliers():
    """Bricard driven: one row of Phi_q depends on the others, so Phi_q^T lam = Q - M q_ddot has
    many solutions; the reported one has no component in the null space of Phi_q^T."""
    functions = casmech.compile(casmech.loads(BRICARD_DRIVEN))
    result = casmech.analyze(functions, t_end=0.5)
    for t, q, lam in zip(result.times, result.q, result.lam, strict=True):
        phi_q = functions.matrix("phi_q", t, q)
        null = np.linalg.svd(phi_q.T)[2][-1]  # phi_q^T (35 x 36) has a one-dimensional null space
        # roundoff of a minimum-norm solve on multipliers of ~1e1 N
        assert abs(null @ lam) <= 1e-11 * max(1.0, np.max(np.abs(lam)))


@pytest.mark.parametrize("mode", ["interpreted", "compiled"])
def test_function_calls_do_not_grow_with_rows(monkeypatch, quick_builds, mode):
    """No Python per output row: the four-bar's 101 and 1001 rows take the same CasADi calls."""
    functions = casmech.compile(casmech.load(MODELS / "four_bar.yaml"), mode)
    # a first run builds the interpreted bundle's functions (built on first use; their
    # traced steps are symbolic calls, a build cost, not a per-row one)
    casmech.analyze(functions, "kinematics", t_end=0.02, output_step=0.01)
    calls = count_calls(monkeypatch)
    counts = {}
    for t_end in (1.0, 10.0):
        calls.clear()
        result = casmech.analyze(functions, "kinematics", t_end=t_end, output_step=0.01)
        counts[len(result)] = len(calls)
    assert set(counts) == {101, 1001}
    assert counts[101] == counts[1001] > 0


def test_long_grids_in_blocks_give_the_same_rows():
    """A grid longer than solver.max_block is called in blocks, each starting from the row
    before it: the same rows, bit for bit, as one call over the grid."""
    functions = casmech.compile(casmech.load(MODELS / "four_bar.yaml"), "interpreted")
    whole = casmech.analyze(functions, "kinematics", t_end=3.0, output_step=0.01)
    blocks = casmech.analyze(functions, "kinematics", t_end=3.0, output_step=0.01,
                             options={"max_block": 64})
    assert len(whole) == len(blocks) == 301 and whole.metadata["per_row_rows"] == 0
    for name in ("times", "q", "q_dot", "q_ddot", "lam"):
        np.testing.assert_array_equal(getattr(blocks, name), getattr(whole, name), err_msg=name)


@pytest.mark.parametrize("driver, failed_at, cause", [
    ("(1 - t)**2", 1.0, "singular configuration: the constraint Jacobian lost rank (6 < 7)"),
    ("1 - t", 1.01, "the constraints cannot be met: positions did not converge"),
])
def test_failures_are_located_and_rows_before_them_kept(driver, failed_at, cause):
    """A slider held at distance sqrt(f(t)) from the origin: with f = (1 - t)^2 it passes the
    origin at t = 1, where the tether's row of Phi_q vanishes; with f = 1 - t no position
    exists after t = 1. The mapped step rejects that row and the per-row code reports it from
    the last kept state; the rows kept equal the per-row loop's."""
    functions = casmech.compile(casmech.loads(SLIDER % driver))
    with pytest.raises(AnalysisError) as failure:
        casmech.analyze(functions)
    message = str(failure.value)
    assert f"analysis failed at t = {failed_at:g}: {cause}" in message
    assert "<string>:9:5: joint 'tether'" in message  # located at the joint in the model text
    partial = failure.value.partial
    assert partial.times[-1] < failed_at and len(partial) == round(failed_at / 0.01)
    t, q, q_dot, q_ddot = partial.times[-1], partial.q[-1], partial.q_dot[-1], partial.q_ddot[-1]
    h = failed_at - t
    with pytest.raises(AnalysisError) as per_row_failure:
        state_at(functions, failed_at, q + h * q_dot + 0.5 * h * h * q_ddot, q_dot + h * q_ddot)
    assert str(per_row_failure.value) == message
    rows, _ = per_row(functions, 2.0, 0.01)
    times = np.array(partial.times)
    # away from the double root of |x|^2 = f at t = 1, where Newton converges linearly and stops
    # at |Phi| = x^2 <= 1e-12: both loops converge Newton to |Phi| <= 1e-12 on O(1) lengths
    smooth = times < 0.95
    expected = np.array([row[1] for row in rows[:len(times)]])
    np.testing.assert_allclose(partial.q[smooth], expected[smooth], rtol=0, atol=1e-11)
