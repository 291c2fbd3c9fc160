"""Assembly: positions from the file's pose, drivers reached by continuation, velocities
projected onto the constraints, accelerations and reactions from the equations of motion."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.core.options import Assembly, LinearAlgebra
from casmech.equations.checks import structure
from casmech.errors import AnalysisError
from casmech.numerics import kkt
from casmech.runtime import assembly
from tests.conftest import MODELS, Table

DEFAULT = Assembly()  # the assembly's settings (casmech.core.options)

M, L, G, I_CM = 2.0, 1.2, 9.81, 0.3  # mass, CM distance from the pivot, gravity, inertia about x


def pendulum(theta0=0.0, omega0=0.0, driver=None, extra_joint="", file_velocity=None):
    """A pendulum about global x at the origin, CM at distance L, drawn at angle theta0."""
    r = [0.0, L * np.sin(theta0), -L * np.cos(theta0)]
    v = file_velocity or [0.0, L * np.cos(theta0) * omega0, L * np.sin(theta0) * omega0]
    r, v = ([float(x) for x in vector] for vector in (r, v))
    driver_text = f"\n    driver: {{angle: '{driver}'}}" if driver else ""
    return f"""
casmech: 1
name: pendulum
gravity: [0, 0, -{G}]
bodies:
  - name: bar
    mass: {M}
    inertia: [{I_CM}, {I_CM}, 0.01]
    position: {r}
    orientation: {{axis_angle: {{axis: [1, 0, 0], angle: {theta0}}}}}
    velocity: {v}
    angular_velocity: [{omega0}, 0, 0]
joints:
  - name: pivot
    type: revolute
    body_i: ground
    body_j: bar
    at: [0, 0, 0]
    axis: [1, 0, 0]{driver_text}
{extra_joint}
analysis: {{type: assembly}}
"""


def assemble(text):
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions, "assembly")
    return Table(*casmech.results_table(functions, result))


def angle_of(table):
    return np.arctan2(table["bar.y"], -table["bar.z"])[0]


@pytest.mark.parametrize("target", [0.7, 3.0, -3.0, 2.5 * np.pi, 10.0])
def test_driver_continuation_reaches_the_driven_angle_not_its_mirror(target):
    """sin(theta - f) also vanishes at theta = f + pi; continuation must not land there."""
    table = assemble(pendulum(driver=f"{target} + 0*t"))
    wrapped = (target + np.pi) % (2 * np.pi) - np.pi
    # Newton converges to |Phi| <= 1e-12
    np.testing.assert_allclose(angle_of(table), wrapped, rtol=0, atol=1e-10)


@pytest.mark.parametrize("theta0, omega0", [(0.4, 0.0), (-1.1, 2.5), (2.0, -1.0)])
def test_free_pendulum_accelerations_and_reaction_from_eom(theta0, omega0):
    """At any instant: I_O theta'' = -m g L sin(theta); the joint force on the bar is
    m (a_cm - g), a_cm with tangential L theta'' and centripetal L theta'^2 parts."""
    table = assemble(pendulum(theta0, omega0))
    i_o = I_CM + M * L**2
    alpha = -M * G * L * np.sin(theta0) / i_o
    # closed form vs a linear solve of a 14x14 system: roundoff only
    np.testing.assert_allclose(table["bar.alphax"], alpha, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(table["bar.wx"], omega0, rtol=1e-12, atol=1e-12)
    a_cm = np.array([0.0,
                     L * (np.cos(theta0) * alpha - np.sin(theta0) * omega0**2),
                     L * (np.sin(theta0) * alpha + np.cos(theta0) * omega0**2)])
    force = M * (a_cm - np.array([0, 0, -G]))
    for k, axis in enumerate("xyz"):
        np.testing.assert_allclose(table[f"bar.a{axis}"], a_cm[k], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(table[f"pivot.f{axis}"], force[k], rtol=1e-10, atol=1e-10)
    # an undriven revolute transmits no torque about its own axis
    np.testing.assert_allclose(table["pivot.tx"], 0, rtol=0, atol=1e-10)


def test_file_velocities_are_projected_onto_the_constraints():
    """A velocity along the joint axis violates the revolute; assembly removes it and keeps the
    compatible part."""
    table = assemble(pendulum(0.0, 0.0, file_velocity=[1.0, 0.5, 0.0]))
    np.testing.assert_allclose(table["bar.vx"], 0, rtol=0, atol=1e-12)  # roundoff
    assert table["bar.vy"][0] > 0.1  # the compatible swing velocity survives


def test_assembly_failure_names_the_joint():
    """A distance constraint that no pose satisfies (tip 5 m away from a point 10 m up)."""
    impossible = """  - {name: tether, type: d, body_i: ground, s_i: [0, 0, 10], body_j: bar,
     s_j: [0, 0, -0.5], f: "1"}"""
    functions = casmech.compile(casmech.loads(pendulum(extra_joint=impossible)))
    with pytest.raises(AnalysisError) as failure:
        casmech.analyze(functions, "assembly")
    message = str(failure.value)
    assert "did not converge" in message and "joint 'tether'" in message
    assert "<string>:" in message  # the joint's location in the model text


def test_progress_is_called_with_every_row_time():
    """analyze(progress=...) sees each output time once, in order, as rows are made."""
    functions = casmech.compile(casmech.load(MODELS / "me751_pendulum.yaml"))
    seen = []
    result = casmech.analyze(functions, t_end=0.05, progress=seen.append)
    assert seen == result.times


# Sparse linear algebra (numerics.numeric_qr) against the dense numpy code it replaced; the
# gallery's matrices are below numeric_qr's dense limits, so its sparse path and its dense QR
# path are forced.


@pytest.fixture(params=["sparse", "dense_qr"])
def sparse(request) -> Assembly:
    """Assembly settings whose linear algebra takes the sparse path, or LAPACK's QR."""
    dense_qr = 0 if request.param == "sparse" else LinearAlgebra().dense_qr_entries
    return Assembly(linear_algebra=LinearAlgebra(dense_entries=0, dense_qr_entries=dense_qr))


DENSE_CASES = [*sorted(MODELS.glob("*.yaml")),
               MODELS / "validation" / "iftomm_a02_four_bar_N2.yaml"]


def dense_newton(functions, q, scale=None, tolerance=DEFAULT.tolerance):
    q = np.array(q, float)
    for _ in range(DEFAULT.max_iterations):
        if scale is None:
            phi, phi_q = functions.vector("phi", 0.0, q), functions.matrix("phi_q", 0.0, q)
        else:
            phi, phi_q = functions.evaluate("phi_scaled", 0.0, q, scale)
        if np.max(np.abs(phi), initial=0.0) <= tolerance:
            break
        q += np.linalg.lstsq(phi_q, -np.ravel(phi), rcond=None)[0]
    return q


def dense_initial_state(functions, q):
    steps = max(1, int(np.ceil(assembly.driver_span(functions, 0.0) / DEFAULT.max_driver_step)))
    for k in range(1, steps + 1):
        q = dense_newton(functions, q, k / steps, 1e-8 if k < steps else 1e-12)
    q = dense_newton(functions, q)
    phi_q, nu = functions.matrix("phi_q", 0.0, q), functions.vector("nu", 0.0, q)
    guess = assembly.file_velocities(functions, q)
    return q, guess + np.linalg.lstsq(phi_q, nu - phi_q @ guess, rcond=None)[0]


@pytest.mark.parametrize("path", DENSE_CASES, ids=lambda path: path.stem)
def test_least_squares_stage_equals_the_dense_code(path, sparse):
    """From the file's pose and from a pose 1e-3 away (so Newton takes real steps). Bricard
    from the perturbed pose is left out: near the solution its Phi_q has a singular value
    of 1e-13 of the largest (the redundant row), which dense lstsq still inverts (|Phi| went
    from 2.6e-12 to 2.7e-9 in that step, measured) while the sparse code takes that row as
    dependent; both end assembled, 6e-5 apart along the mechanism's motion."""
    functions = casmech.compile(casmech.load(path))
    guess = assembly.initial_guess(functions)
    starts = [guess]
    if path.stem != "bricard":
        starts.append(guess + 1e-3 * np.random.default_rng(0).standard_normal(guess.size))
    for start in starts:
        q = assembly.least_squares_positions(functions, 0.0, start, sparse)
        q_dot = assembly.solve_velocities(functions, 0.0, q, assembly.file_velocities(functions, q),
                                          sparse)
        dense_q, dense_q_dot = dense_initial_state(functions, start)
        # the same Newton steps up to roundoff, both stopped at |Phi| <= 1e-12: measured <= 4e-18
        np.testing.assert_allclose(q, dense_q, rtol=0, atol=1e-13)
        # velocities of O(1..50): roundoff of the solves, measured <= 1e-14
        np.testing.assert_allclose(q_dot, dense_q_dot, rtol=0, atol=1e-12)


def off_the_constraints(path, size=1e-2, seed=0):
    """The model's bundle and its file pose moved by `size` (random, every coordinate)."""
    functions = casmech.compile(casmech.load(path))
    guess = assembly.initial_guess(functions)
    return functions, guess + size * np.random.default_rng(seed).standard_normal(guess.size)


def normal_part(functions, q, direction):
    """The part of `direction` outside range(Phi_q(q)^T) (0 for a KKT point's q - q_ref)."""
    phi_q = functions.matrix("phi_q", 0.0, q)
    return direction - phi_q.T @ np.linalg.lstsq(phi_q.T, direction, rcond=None)[0]


@pytest.mark.parametrize("model", ["double_pendulum", "flyball_governor", "triple_pendulum",
                                   "heavy_top"])
def test_assembled_pose_is_the_closest_point_with_degrees_of_freedom(model):
    """q - q_ref in range(Phi_q^T) (first-order optimality of min |q - q_ref| on Phi = 0),
    where the least-squares Newton's end point is not, and nearer to q_ref than that one."""
    functions, reference = off_the_constraints(MODELS / f"{model}.yaml")
    q = assembly.assemble_positions(functions, 0.0, reference)
    newton_q = assembly.least_squares_positions(functions, 0.0, reference)
    assert np.max(np.abs(functions.vector("phi", 0.0, q))) <= DEFAULT.tolerance
    # the rootfinder stops at |KKT residual| <= 1e-14 (measured <= 1e-13 after the lstsq split)
    np.testing.assert_allclose(normal_part(functions, q, q - reference), 0, rtol=0, atol=1e-10)
    # Newton's point is off by O(1e-2 ^ 2) (measured 4e-6..2e-4): the polish did the work
    assert np.max(np.abs(normal_part(functions, newton_q, newton_q - reference))) > 1e-7
    assert np.linalg.norm(q - reference) < np.linalg.norm(newton_q - reference)


def test_closest_point_of_a_compiled_bundle(quick_builds):
    """Through the C functions (the rootfinder's Jacobian then differentiates the externals'
    phi_q by its generated forward derivative): the interpreted bundle's point."""
    points = []
    for mode in ("interpreted", "compiled"):
        functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"), mode)
        guess = assembly.initial_guess(functions)
        reference = guess + 1e-2 * np.random.default_rng(0).standard_normal(guess.size)
        points.append(assembly.assemble_positions(functions, 0.0, reference))
        assert np.max(np.abs(points[-1] - assembly.least_squares_positions(
            functions, 0.0, reference))) > 1e-6  # the rootfinder moved it
    # the same expressions evaluated in C and by CasADi's VM: roundoff (measured 1.1e-16)
    np.testing.assert_allclose(points[1], points[0], rtol=0, atol=1e-13)


@pytest.mark.parametrize("model", ["four_bar", "slider_crank", "spatial_rsur"])
def test_fully_driven_pose_is_the_least_squares_one(model):
    """Without degrees of freedom the root is isolated: the rootfinder from Newton's point
    stays there, which is why assembly does not call it then."""
    functions, reference = off_the_constraints(MODELS / f"{model}.yaml", 1e-3)
    newton_q = assembly.least_squares_positions(functions, 0.0, reference)
    rows = structure(functions, 0.0, newton_q).independent
    assert len(rows) == functions.n_coordinates
    closest = kkt.closest_point(functions["phi"], functions["phi_q"], rows)
    q = np.array(closest(newton_q, 0.0, reference)[0]).ravel()
    # both converged to the same root (|Phi| <= 1e-12 and O(1) Jacobians): measured <= 1e-15
    np.testing.assert_allclose(q, newton_q, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(assembly.assemble_positions(functions, 0.0, reference),
                                  newton_q)


def test_a_pose_on_the_constraints_is_kept():
    """The closest point of a pose that meets Phi = 0 is itself: returned as it is."""
    functions = casmech.compile(casmech.load(MODELS / "four_bar.yaml"))
    guess = assembly.initial_guess(functions)
    assert np.max(np.abs(functions.vector("phi", 0.0, guess))) <= DEFAULT.tolerance
    np.testing.assert_array_equal(assembly.assemble_positions(functions), guess)


@pytest.mark.parametrize("model", ["bricard", "flyball_governor", "four_bar", "quadruped_legs"])
def test_dynamic_accelerations_equal_the_dense_least_squares(model):
    """[M Phi_q^T; Phi_q 0] [q_ddot; lam] = [Q; gamma] (numerics.kkt.saddle over the
    independent rows); singular with Bricard's redundant row, where lstsq gives the
    minimum-norm multipliers."""
    functions = casmech.compile(casmech.load(MODELS / f"{model}.yaml"))
    q, _ = assembly.initial_state(functions)
    q_dot = assembly.solve_velocities(functions, 0.0, q, np.ones_like(q))  # moving: gamma != 0
    q_ddot, lam = assembly.solve_dynamic_accelerations(functions, 0.0, q, q_dot)
    mass, phi_q = functions.matrix("mass_matrix", q), functions.matrix("phi_q", 0.0, q)
    m = phi_q.shape[0]
    lhs = np.block([[mass, phi_q.T], [phi_q, np.zeros((m, m))]])
    rhs = np.concatenate([functions.vector("generalized_forces", 0.0, q, q_dot),
                          functions.vector("gamma", 0.0, q, q_dot)])
    expected = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    scale = np.max(np.abs(expected))
    # roundoff of two factorizations of a KKT matrix with condition ~1e3..1e5
    np.testing.assert_allclose(np.concatenate([q_ddot, lam]), expected, rtol=0,
                               atol=1e-10 * scale)


def test_projection_equals_the_dense_solve():
    """project's damped Gauss-Newton steps (formulations.augmented.projection's sparse LDL) against
    dense NumPy iterations, from a drifted state."""
    from casmech.formulations.table import BODY_FORMS

    functions = casmech.compile(casmech.load(MODELS / "flyball_governor.yaml"))
    q, v = assembly.initial_state(functions)
    rng = np.random.default_rng(2)
    q, v = q + 1e-4 * rng.standard_normal(q.size), v + 1e-3 * rng.standard_normal(v.size)
    form, penalty = BODY_FORMS["rp"], 1e6
    projected_q, projected_v = assembly.project(functions, form, 0.0, q, v, penalty)
    mass = functions.matrix("mass_matrix", q)
    dense_q = q.copy()
    for _ in range(DEFAULT.max_iterations):
        phi = functions.vector("phi", 0.0, dense_q)
        if np.max(np.abs(phi)) <= DEFAULT.tolerance:
            break
        jac = functions.matrix("phi_q", 0.0, dense_q)
        dense_q = dense_q - np.linalg.solve(mass / penalty + jac.T @ jac, jac.T @ phi)
    jac = functions.matrix("phi_q", 0.0, dense_q)
    residual = jac @ v - functions.vector("nu", 0.0, dense_q)
    dense_v = v - np.linalg.solve(functions.matrix("mass_matrix", dense_q) / penalty
                                  + jac.T @ jac, jac.T @ residual)
    # the same iterations up to roundoff (condition of M / a + P^T P ~1e6)
    np.testing.assert_allclose(projected_q, dense_q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(projected_v, dense_v, rtol=0, atol=1e-10)


def test_velocities_from_rest_without_drivers_need_no_solve(monkeypatch):
    """nu structurally zero and a zero guess: q_dot = 0 exactly, without evaluating Phi_q; a
    driven model at rest still solves (its nu is not zero)."""
    from casmech.runtime.assembly import solve_velocities
    from tests.conftest import count_calls

    free = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    driven = casmech.compile(casmech.load(MODELS / "four_bar.yaml"))
    q_free, q_driven = (assembly.assemble_positions(f) for f in (free, driven))
    calls = count_calls(monkeypatch)
    assert not np.any(solve_velocities(free, 0.0, q_free, np.zeros(len(q_free))))
    assert calls == []
    q_dot = solve_velocities(driven, 0.0, q_driven, np.zeros(len(q_driven)))
    assert "phi_q" in calls
    # the driven four-bar's crank turns from t = 0: the velocities satisfy Phi_q q_dot = nu
    np.testing.assert_allclose(driven.matrix("phi_q", 0.0, q_driven) @ q_dot,
                               driven.vector("nu", 0.0, q_driven), rtol=0, atol=1e-12)
    assert np.any(q_dot)


def test_saddle_solution_of_a_singular_system_is_the_least_squares_one():
    """A pendulum's constraint rows with its first row repeated: the KKT matrix is singular,
    the LU of kkt.saddle refuses it and saddle_solution gives numpy's least-squares solution."""
    functions = casmech.compile(casmech.loads(pendulum(0.4, 1.0)))
    q, q_dot = assembly.initial_state(functions)
    mass, phi_q = functions["mass_matrix"](q), functions["phi_q"](0.0, q)
    phi_q = ca.vertcat(phi_q, phi_q[0, :])
    gamma = functions.vector("gamma", 0.0, q, q_dot)
    gamma = np.append(gamma, gamma[0])
    forces, w = functions["generalized_forces"](0.0, q, q_dot), np.zeros(len(gamma))
    saddle = kkt.saddle(mass.sparsity(), phi_q.sparsity())
    with pytest.raises(RuntimeError, match="singular"):
        saddle(mass, phi_q, forces, gamma, w)
    v_dot, lam = assembly.saddle_solution(saddle, mass, phi_q, forces, gamma, w)
    lhs = np.block([[np.array(mass), np.array(phi_q).T],
                    [np.array(phi_q), np.zeros((len(w), len(w)))]])
    expected = np.linalg.lstsq(lhs, np.concatenate([np.array(forces).ravel(), gamma]),
                               rcond=None)[0]
    # the same dense lstsq call: identical
    np.testing.assert_allclose(np.concatenate([v_dot, lam]), expected, rtol=0, atol=0)
