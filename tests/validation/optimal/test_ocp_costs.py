"""Cost terms of `ocp:` (optimal/costs.py): Lagrange terms on expressions of the state, Mayer
terms and tracking of a table, against closed forms (a discrete Riccati recursion of the exact
zero-order-hold LQR, the continuous Riccati equation, a Mayer problem solved by hand, a
reachable reference)."""

import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import solve_ivp

import casmech
from casmech.errors import ModelError, UsageError
from casmech.optimal.ocp import OCP, columns_at, from_block, solve

MASS = 2.0

# a slider on the y axis without gravity: y'' = F / m (a double integrator)
SLIDER = """
casmech: 1
name: slider
parameters: {{m: {mass}, y0: 1.0, q: 3.0, s: 5.0}}
gravity: [0, 0, 0]
bodies:
  - {{name: block, mass: m, inertia: [0.1, 0.1, 0.1], position: [0, y0, 0]}}
joints:
  - {{name: slide, type: translational, body_i: ground, body_j: block, at: [0, 0, 0],
     axis: [0, 1, 0]}}
ocp:
{ocp}
"""

LQR = """  horizon: 2.0
  intervals: {intervals}
  formulation: joints
  controls: [{{joint: slide, type: force}}]
  objective:
    effort: 0.5
    integral: {{block.y: q, slide.displacement_dot: 1}}
    final: s * block.y**2"""


def slider(ocp: str, tmp_path=None, **values):
    text = SLIDER.format(mass=MASS, ocp=ocp.format(**values) if values else ocp)
    if tmp_path is None:
        return casmech.loads(text)
    path = tmp_path / "slider.yaml"
    path.write_text(text)
    return casmech.load(path)


def zero_order_hold_lqr(step: float, intervals: int, q: np.ndarray, r: float, s: np.ndarray):
    """(P_0, gains) of the exact discretisation of x' = A x + B u, cost int x^T Q x + r u^2 dt
    + x(T)^T S x(T), with u constant on each interval (Van Loan's integrals)."""
    a = np.array([[0.0, 1.0], [0.0, 0.0]])
    b = np.array([[0.0], [1.0 / MASS]])
    c = np.zeros((3, 3))
    c[:2, :2], c[:2, 2:] = a, b
    weight = scipy.linalg.block_diag(q, [[r]])
    block = np.zeros((6, 6))
    block[:3, :3], block[:3, 3:], block[3:, 3:] = -c.T, weight, c
    exp = scipy.linalg.expm(block * step)
    z = exp[3:, 3:].T @ exp[:3, 3:]  # int_0^h e^{C^T t} W e^{C t} dt
    z = 0.5 * (z + z.T)
    ad, bd = exp[3:, 3:][:2, :2], exp[3:, 3:][:2, 2:]
    p, gains = s, []
    for _ in range(intervals):
        gain = np.linalg.solve(z[2:, 2:] + bd.T @ p @ bd, z[2:, :2] + bd.T @ p @ ad)
        p = z[:2, :2] + ad.T @ p @ ad - (z[:2, 2:] + ad.T @ p @ bd) @ gain
        gains.append(gain)
    return p, gains[::-1], (ad, bd)


def test_a_state_quadratic_cost_is_the_riccati_solution():
    """min 0.5 int F^2 + q y^2 + v^2 dt + s y(T)^2 from y = 1 at rest. With F constant per
    interval, Radau collocation of degree 3 is exact (y is quadratic in t there) and so is its
    quadrature of the running cost (degree 4 in t): the optimum is the discrete Riccati
    recursion's x0^T P_0 x0, and its controls the recursion's feedback."""
    q, s, r, intervals, horizon = 3.0, 5.0, 0.5, 20, 2.0
    model = slider(LQR, intervals=intervals)
    problem, transcription = from_block(model.ocp)
    solution = solve(model, problem, transcription)
    assert solution.status == "Solve_Succeeded"
    x0 = np.array([1.0, 0.0])
    p0, gains, (ad, bd) = zero_order_hold_lqr(horizon / intervals, intervals,
                                              np.diag([q, 1.0]), r, np.diag([s, 0.0]))
    # the same finite-dimensional problem to IPOPT's tolerance (tol 1e-10)
    np.testing.assert_allclose(solution.objective, x0 @ p0 @ x0, rtol=1e-8, atol=0)
    x, controls = x0, []
    for gain in gains:
        controls.append(float(-(gain @ x)[0]))
        x = ad @ x + bd.ravel() * controls[-1]
    np.testing.assert_allclose(solution.u[:, 0], controls, rtol=0, atol=1e-6)  # N, as above
    # the continuous LQR (Riccati's differential equation, backwards from S) bounds the
    # piecewise-constant optimum from below, within O(h^2) (measured 1.3e-3 relative)
    a, b = np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0 / MASS]])

    def riccati(_, flat):
        pm = flat.reshape(2, 2)
        return -(a.T @ pm + pm @ a - pm @ b @ b.T @ pm / r + np.diag([q, 1.0])).ravel()

    back = solve_ivp(riccati, (horizon, 0.0), np.diag([s, 0.0]).ravel(), rtol=1e-12,
                     atol=1e-12)
    continuous = x0 @ back.y[:, -1].reshape(2, 2) @ x0
    assert continuous <= solution.objective <= continuous * 1.01


def test_shooting_integrates_the_running_cost_by_rk4():
    """The same problem by multiple shooting: RK4's stages integrate the running cost with
    the state (fourth order), so the optimum is the collocation's to RK4's error."""
    model = slider(LQR, intervals=20)
    problem, _ = from_block(model.ocp)
    collocated = solve(model, problem, "collocation")
    shot = solve(model, OCP(**{**problem.__dict__, "steps": 8}), "shooting")
    # RK4 is exact on y and v (polynomials of degree 2) but not on the degree-4 running cost:
    # 8 steps of 0.0125 s leave ~1e-9 relative (measured 2e-10)
    np.testing.assert_allclose(shot.objective, collocated.objective, rtol=1e-7, atol=0)


def test_a_mayer_term_rewards_the_final_angle_in_closed_form():
    """min int tau^2 dt - a theta(T) on J theta'' = tau from rest: theta(T) = int (T - t)
    tau / J dt, so tau = a (T - t) / (2 J) and the cost is -a^2 T^3 / (12 J^2); linear in t,
    so piecewise-linear controls and Radau collocation (a cubic angle) hold it exactly. The
    final angle passes pi, where the results table's spin.angle jumps to -pi: the cost term
    reads it continued (optimal/costs.py)."""
    j, a, horizon = 0.5, 0.7, 2.0  # theta(T) = a T^3 / (6 J^2) = 3.7 rad: past pi
    model = casmech.loads(f"""
casmech: 1
name: disk
parameters: {{J: {j}, a: {a}}}
bodies:
  - {{name: disk, mass: 2.0, inertia: [0.3, 0.3, J], position: [0, 0, 0]}}
joints:
  - {{name: spin, type: revolute, body_i: ground, body_j: disk, at: [0, 0, 0],
     axis: [0, 0, 1]}}
ocp:
  horizon: {horizon}
  intervals: 6
  piecewise: linear
  controls: [{{joint: spin}}]
  objective: {{final: -a * spin.angle}}
""")
    problem, transcription = from_block(model.ocp)
    solution = solve(model, problem, transcription)
    torque = a * (horizon - solution.times) / (2 * j)
    np.testing.assert_allclose(solution.u[:, 0], torque, rtol=0, atol=1e-6)  # IPOPT's tol
    np.testing.assert_allclose(solution.objective, -a ** 2 * horizon ** 3 / (12 * j ** 2),
                               rtol=1e-8, atol=0)  # the same, relative


def test_tracking_a_reachable_table_takes_its_controls(tmp_path):
    """Track the block's velocity to a table that is piecewise linear with its breaks at the
    nodes: piecewise-constant forces m * slope follow it exactly, the only controls at which
    the (effort-free) cost is zero."""
    rng = np.random.default_rng(3)
    intervals, horizon = 8, 2.0
    times = np.linspace(0, horizon, intervals + 1)
    slopes = rng.uniform(-1, 1, intervals)
    speed = np.concatenate([[0.0], np.cumsum(slopes * horizon / intervals)])
    lines = ["t,speed"] + [f"{t:.17g},{v:.17g}" for t, v in zip(times, speed, strict=True)]
    (tmp_path / "reference.csv").write_text("\n".join(lines) + "\n")
    ocp = f"""  horizon: {horizon}
  intervals: {intervals}
  controls: [{{joint: slide, type: force}}]
  objective:
    effort: 0
    track: {{block.vy: {{table: reference.csv, column: speed, interpolation: linear,
                         weight: 10}}}}"""
    model = slider(ocp, tmp_path)
    problem, transcription = from_block(model.ocp)
    solution = solve(model, problem, transcription)
    # the reference is met exactly: cost zero, forces m * slope (IPOPT's tol 1e-10)
    np.testing.assert_allclose(solution.u[:, 0], MASS * slopes, rtol=0, atol=1e-6)
    assert abs(solution.objective) < 1e-10
    vy = columns_at(model, problem, solution, ["block.vy"])[:, 0]
    np.testing.assert_allclose(vy, speed, rtol=0, atol=1e-8)  # m/s, the same tolerance


@pytest.mark.parametrize("objective, code, where", [
    ("{integral: {block.yy: 1}}", "E201", "block.yy"),
    ("{final: 2 * slide.angle}", "E201", "has no 'angle'"),
    ("{track: {block.y: {table: ../outside.csv}}}", "E305", "outside"),
    ("{track: {block.y: {table: missing.csv}}}", "E300", "missing.csv"),
    ("{track: {block.q: {table: missing.csv}}}", "E201", "block.q"),
    ("{integral: {block.y: -1}}", "E409", "at least 0"),
])
def test_bad_cost_terms_are_located_errors(tmp_path, objective, code, where):
    ocp = f"""  horizon: 1
  controls: [{{joint: slide, type: force}}]
  objective: {objective}"""
    with pytest.raises(ModelError) as raised:
        slider(ocp, tmp_path)
    text = str(raised.value)
    assert f"error[{code}]" in text and where in text and "slider.yaml:" in text


def test_cost_terms_need_joint_coordinates():
    model = slider(LQR, intervals=4)
    problem, _ = from_block(model.ocp)
    with pytest.raises(UsageError, match="joint coordinates only"):
        solve(model, OCP(**{**problem.__dict__, "formulation": "bodies"}), "collocation")


def test_the_api_takes_expressions_as_text():
    """OCP(integral={text: weight}, final=text) from Python: the YAML problem's optimum."""
    model = slider(LQR, intervals=6)
    problem, transcription = from_block(model.ocp)
    texts = OCP(**{**problem.__dict__, "integral": {"block.y": 3.0,
                                                   "slide.displacement_dot": 1.0},
                   "final": "s * block.y**2"})
    # the same NLP: equal to roundoff
    np.testing.assert_allclose(solve(model, texts, transcription).objective,
                               solve(model, problem, transcription).objective,
                               rtol=1e-12, atol=0)
