"""Linearization at a time of a dynamics run (`analysis: {type: modal, at: ...}`, runtime/modal.py
and runtime/linearize.py) against closed forms and a finite-difference linearization of casmech's
own dynamics in the same independent coordinates (issue 17 item 2, brief 'linearize')."""

import numpy as np
import pytest

import casmech
from casmech.errors import AnalysisError, ModelError, UsageError
from casmech.runtime import assembly, modal, statics
from tests.conftest import MODELS
from tests.helpers.statics_models import HANGING_FOUR_BAR, HANGING_ROD, SPRING_MASS, G

TIGHT = "rtol: 1e-10, atol: 1e-12"


def at_time(text: str, at: float, extra: str = "") -> str:
    """A model text whose analysis is modal at `at` (t_end 1 s) with tight tolerances."""
    head, _, _ = text.rpartition("\nanalysis:")  # the analysis block is each model's last
    return head + f"\nanalysis: {{type: modal, at: {at}, t_end: 1, {TIGHT}{extra}}}\n"


def run(text: str):
    functions = casmech.compile(casmech.loads(text))
    return functions, casmech.analyze(functions)


def chart_ode(functions, t, q_star, basis, x):
    """x' = f(x) of the chart z = N^T (q - q*), w = N^T q_dot, evaluated with casmech's own
    numeric pieces and no AD through them: q on Phi = 0 by Newton on [Phi; N^T (q - q*) - z],
    q_dot from [Phi_q; N^T] q_dot = [nu; w] and q_ddot from assembly.solve_dynamic_accelerations
    (least squares, redundant rows allowed)."""
    k = basis.shape[1]
    z, w = x[:k], x[k:]
    q = q_star + basis @ z
    for _ in range(30):
        residual = np.concatenate([functions.vector("phi", t, q), basis.T @ (q - q_star) - z])
        if np.max(np.abs(residual)) < 1e-15:
            break
        jacobian = np.vstack([functions.matrix("phi_q", t, q), basis.T])
        q = q - np.linalg.lstsq(jacobian, residual, rcond=None)[0]
    jacobian = np.vstack([functions.matrix("phi_q", t, q), basis.T])
    q_dot = np.linalg.lstsq(jacobian, np.concatenate([functions.vector("nu", t, q), w]),
                            rcond=None)[0]
    q_ddot = assembly.solve_dynamic_accelerations(functions, t, q, q_dot)[0]
    return np.concatenate([basis.T @ q_dot, basis.T @ q_ddot])


def finite_difference_a(functions, model, eps=1e-5):
    """Central differences of chart_ode about the model's state."""
    k = model.basis.shape[1]
    x = np.concatenate([np.zeros(k), model.basis.T @ model.q_dot])
    columns = []
    for j in range(2 * k):
        step = np.zeros(2 * k)
        step[j] = eps
        columns.append((chart_ode(functions, model.t, model.q, model.basis, x + step)
                        - chart_ode(functions, model.t, model.q, model.basis, x - step))
                       / (2 * eps))
    return np.column_stack(columns)


def pendulum_angle(model):
    """The rod's angle about y and its rate, from its Euler parameters (p = (cos th/2, 0,
    sin th/2, 0)) and their rates."""
    e, e_dot = model.q[3:], model.q_dot[3:]
    return 2 * np.arctan2(e[2], e[0]), 2 * (e[0] * e_dot[2] - e[2] * e_dot[0])


def test_pendulum_stiffness_at_a_time_of_its_swing_is_the_closed_form():
    m, length, w = 1.5, 0.8, 0.03  # HANGING_ROD's parameters, released at theta0 = 0.7
    functions, result = run(at_time(HANGING_ROD, 0.3))
    model = result.linear_model
    assert model.t == pytest.approx(0.3, rel=0, abs=1e-15) and result.times[-1] == model.t
    assert result.metadata["linearized_at"] == "t = 0.3"
    theta, rate = pendulum_angle(model)
    assert abs(rate) > 1.0  # mid-swing: the velocity term matters
    arm = length / 2
    inertia = m * (length**2 + w**2) / 12 + m * arm**2
    # theta'' = -(m g l / J) sin theta; in the chart z = N^T (q - q*) (q holds the CM position
    # l (-sin, 0, -cos) and the Euler parameters, |dq/dtheta|^2 = l^2 + 1/4) the chart's
    # curvature adds c''/c theta_dot^2 with c(theta) = N^T dq/dtheta:
    # -(l^2 + 1/16) / (l^2 + 1/4) theta_dot^2 (docs/analyses.md#modal)
    stiffness = -(m * G * arm / inertia) * np.cos(theta) \
        - (arm**2 + 1 / 16) / (arm**2 + 1 / 4) * rate**2
    # theta, theta_dot from a run at rtol 1e-10: rtol 1e-8; the other entries exact (roundoff)
    np.testing.assert_allclose(model.A[1, 0], stiffness, rtol=1e-8, atol=0)
    np.testing.assert_allclose(model.A[0], [0.0, 1.0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(model.A[1, 1], 0.0, rtol=0, atol=1e-10)


def test_pendulum_at_a_turning_point_is_minus_g_over_l_cos_theta():
    # released from rest: at at = 0 the swing turns (theta_dot = 0), no chart term
    m, length, w, theta0 = 1.5, 0.8, 0.03, 0.7
    functions, result = run(at_time(HANGING_ROD, 0))
    model = result.linear_model
    arm = length / 2
    inertia = m * (length**2 + w**2) / 12 + m * arm**2
    # the assembled pose is the file's (exact): rtol 1e-12
    np.testing.assert_allclose(model.A[1, 0], -(m * G * arm / inertia) * np.cos(theta0),
                               rtol=1e-12, atol=0)
    assert len(result.times) == 1 and model.t == 0.0


def spinning_body(omega: float, i1: float, i3: float) -> str:
    return f"""
casmech: 1
name: spinning_body
gravity: [0, 0, 0]
bodies:
  - {{name: top, mass: 2.0, inertia: [{i1}, {i1}, {i3}], position: [0, 0, 0],
     angular_velocity: [0, 0, {omega}]}}
analysis: {{type: modal, at: 0.4, t_end: 1, {TIGHT}}}
"""


def test_spinning_symmetric_body_precesses_at_the_closed_form_rate():
    omega, i1, i3 = 3.0, 1.0, 1.5
    functions, result = run(spinning_body(omega, i1, i3))
    model = result.linear_model
    precession = omega * (i3 - i1) / i1
    # torque-free precession of the spin axis in the body: +-i w (I3 - I1) / I1, the two
    # transverse directions; the free translations are 3 modes at 0 Hz; the spin about the axis
    # adds |s| = w, the Euler-parameter chart's curvature along the spin (q_dot* != 0).
    # A's eigenvalues from a 12 x 12 eig, a run at rtol 1e-10: rtol 1e-8
    np.testing.assert_allclose(model.frequency_hz * 2 * np.pi,
                               [0, 0, 0, precession, precession, omega], rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(model.damping_ratio, 0.0, rtol=0, atol=1e-9)
    # and A is the chart's Jacobian (central differences of casmech's own dynamics)
    reference = finite_difference_a(functions, model)
    # eps 1e-5: truncation ~eps^2 |f'''|, roundoff ~1e-16 / eps (measured 2e-10 on entries up
    # to 4.5): atol 1e-7
    np.testing.assert_allclose(model.A, reference, rtol=0, atol=1e-7)


@pytest.mark.parametrize("name, text, at", [
    ("four-bar, redundant revolutes, r-p DAE", HANGING_FOUR_BAR, 0.35),
    ("double pendulum, joint coordinates", (MODELS / "double_pendulum.yaml").read_text(), 0.6),
])
def test_a_at_a_time_matches_finite_differences_of_the_dynamics(name, text, at):
    functions, result = run(at_time(text, at))
    model = result.linear_model
    assert np.max(np.abs(model.q_dot)) > 0.1  # moving: Coriolis and curvature terms in A
    reference = finite_difference_a(functions, model)
    # central differences with eps 1e-5 of accelerations of O(10): truncation ~eps^2 |f'''|,
    # roundoff of the Newton projection and the least-squares solves ~1e-15 / eps (measured
    # 1e-10 and 2e-9 on entries up to 11): atol 1e-7
    np.testing.assert_allclose(model.A, reference, rtol=0, atol=1e-7, err_msg=name)


def test_at_an_equilibrium_state_the_trajectory_form_is_the_equilibrium_form():
    # the spring-mass-damper at its equilibrium, zero velocity: the AD of the trajectory graph
    # equals the reduced M, C, K form (a second formulation), inputs included
    functions = casmech.compile(casmech.loads(SPRING_MASS))
    equilibrium = statics.solve(functions)
    at_rest = modal.linearize(functions, equilibrium.system, ["spring", "push"])
    state = modal.linearize_at(functions, 0.0, equilibrium.q, np.zeros_like(equilibrium.q),
                               ["spring", "push"])
    # both exact to roundoff on entries O(40): atol 1e-12
    np.testing.assert_allclose(state.A, at_rest.A, rtol=0, atol=1e-12)
    np.testing.assert_allclose(state.B, at_rest.B, rtol=0, atol=1e-12)
    assert state.input_names == at_rest.input_names == ["spring.force", "push.fx", "push.fy",
                                                        "push.fz"]


def test_cli_writes_where_it_linearized(tmp_path):
    import json

    from casmech.cli import main
    from casmech.io.csv import read_csv

    path = tmp_path / "rod.yaml"
    path.write_text(at_time(HANGING_ROD, 0.25).replace("t_end: 1,", "t_end: 1, output_step: 0.05,"))
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    names, rows = read_csv(tmp_path / "out" / "results.csv")
    assert rows[-1, 0] == pytest.approx(0.25, rel=0, abs=1e-15) and rows.shape[0] == 6
    metadata = json.loads((tmp_path / "out" / "metadata.json").read_text())
    assert metadata["result"]["linearized_at"] == "t = 0.25"
    data = np.load(tmp_path / "out" / "linear_model.npz")
    assert str(data["linearized_at"]) == "t = 0.25" and float(data["t"]) == 0.25
    assert data["A"].shape == (2, 2) and data["q_dot"].shape == (7,)


def findings(text: str) -> list:
    with pytest.raises(ModelError) as caught:
        casmech.loads(text, file="m.yaml")
    return caught.value.diagnostics


@pytest.mark.parametrize("at", ["-0.5", "1.5"])
def test_an_at_outside_the_run_is_a_located_error(at):
    text = HANGING_ROD.replace("analysis: {type: modal}", f"analysis: {{type: modal, at: {at}}}")
    (diagnostic,) = findings(text)
    line = text.splitlines().index(f"analysis: {{type: modal, at: {at}}}") + 1
    assert (diagnostic.code, diagnostic.path) == ("E409", "analysis.at")
    assert f"m.yaml:{line}:" in diagnostic.format()


def test_an_unknown_input_is_a_located_error():
    text = SPRING_MASS.replace("analysis: {type: statics}",
                               "analysis: {type: modal, inputs: [spring, sprung]}")
    (diagnostic,) = findings(text)
    assert (diagnostic.code, diagnostic.path) == ("E300", "analysis.inputs[1]")
    assert "sprung" in diagnostic.message and "spring" in (diagnostic.hint or "")
    line = text.splitlines().index("analysis: {type: modal, inputs: [spring, sprung]}") + 1
    assert f"m.yaml:{line}:" in diagnostic.format()


def test_an_at_beyond_an_overridden_t_end_is_a_usage_error():
    functions = casmech.compile(casmech.loads(at_time(HANGING_ROD, 0.5)))
    with pytest.raises(UsageError, match="at = 0.5"):
        casmech.analyze(functions, t_end=0.2)


def test_a_run_stopped_by_an_event_before_at_keeps_its_rows():
    text = at_time(HANGING_ROD, 0.9) + 'events:\n  - {name: bottom, when: "rod.x", action: stop}\n'
    functions = casmech.compile(casmech.loads(text))
    with pytest.raises(AnalysisError, match="before the linearization time") as caught:
        casmech.analyze(functions)
    assert 0 < caught.value.partial.times[-1] < 0.9
