"""Linearization and modes (runtime/modal.py) against closed forms and against a finite-difference
linearization of casmech's own equations of motion (issue 17 item 2 'must show')."""

import numpy as np
import scipy.linalg

import casmech
from casmech.runtime import assembly, statics
from tests.conftest import MODELS
from tests.helpers.statics_models import (
    HANGING_FOUR_BAR,
    HANGING_ROD,
    RSDA_PENDULUM,
    SPRING_MASS,
    G,
    compiled,
    row,
)


def modal(text_or_path, **parameters):
    if isinstance(text_or_path, str):
        functions = compiled(text_or_path, **parameters)
    else:
        functions = casmech.compile(casmech.load(text_or_path))
    return functions, casmech.analyze(functions, "modal")


def test_compound_pendulum_frequency():
    m, length, w = 1.5, 0.8, 0.03  # HANGING_ROD's parameters
    functions, result = modal(HANGING_ROD)
    arm = length / 2
    omega = np.sqrt(m * G * arm / (m * (length**2 + w**2) / 12 + m * arm**2))
    model = result.linear_model
    # one undamped mode; eigenvalues of a 2 x 2 A to ~1e-15 relative at an equilibrium
    # converged to roundoff: rtol 1e-10
    np.testing.assert_allclose(model.frequency_hz, [omega / (2 * np.pi)], rtol=1e-10, atol=0)
    np.testing.assert_allclose(model.damping_ratio, [0.0], rtol=0, atol=1e-12)
    assert model.state_names == ["z1", "z1_dot"]


def test_point_mass_pendulum_is_sqrt_g_over_l():
    # a body of inertia 1e-9 kg m^2 about its CM, hanging 0.5 m below the pivot
    text = HANGING_ROD.replace(
        "inertia: [m * (L**2 + w**2) / 12, m * (L**2 + w**2) / 12, m * w**2 / 6]",
        "inertia: [1e-9, 1e-9, 1e-9]")
    functions, result = modal(text, L=1.0)
    # the inertia changes omega by I / (2 m l^2) = 1.3e-9 relative: rtol 1e-8
    np.testing.assert_allclose(result.linear_model.frequency_hz,
                               [np.sqrt(G / 0.5) / (2 * np.pi)], rtol=1e-8, atol=0)


def test_double_pendulum_two_frequencies():
    model = casmech.load(MODELS / "double_pendulum.yaml")  # equilibrium found from 90 deg
    functions = casmech.compile(model)
    result = casmech.analyze(functions, "modal")
    m1, m2, l1, l2, w = (model.parameters[n] for n in ("m1", "m2", "L1", "L2", "w"))
    i1, i2 = m1 * (l1**2 + w**2) / 12, m2 * (l2**2 + w**2) / 12
    mass = np.array([[i1 + m1 * l1**2 / 4 + m2 * l1**2, m2 * l1 * l2 / 2],
                     [m2 * l1 * l2 / 2, i2 + m2 * l2**2 / 4]])
    stiffness = G * np.diag([l1 * (m1 / 2 + m2), m2 * l2 / 2])
    omega = np.sqrt(scipy.linalg.eigh(stiffness, mass, eigvals_only=True))
    # rtol 1e-10: eigenvalues of a 4 x 4 A at an equilibrium converged to roundoff
    np.testing.assert_allclose(result.linear_model.frequency_hz, omega / (2 * np.pi),
                               rtol=1e-10, atol=0)
    # mode shapes as body motions: only x translations and rotations about y move
    shapes = result.linear_model.mode_shapes
    assert shapes.shape == (2, 2, 6)
    np.testing.assert_allclose(shapes[:, :, [1, 2, 3, 5]], 0.0, rtol=0, atol=1e-10)
    # the first mode swings both rods the same way, the second against each other
    assert shapes[0, 0, 4].real * shapes[0, 1, 4].real > 0
    assert shapes[1, 0, 4].real * shapes[1, 1, 4].real < 0


def test_spring_mass_damper_ratio_and_frequency():
    m, k, c = 3.0, 120.0, 4.0
    functions, result = modal(SPRING_MASS)
    model = result.linear_model
    zeta = c / (2 * np.sqrt(k * m))
    omega = np.sqrt(k / m)
    # closed forms of a 1-DOF oscillator: rtol 1e-12 (a 2 x 2 eigenproblem)
    np.testing.assert_allclose(model.damping_ratio, [zeta], rtol=1e-12, atol=0)
    np.testing.assert_allclose(model.frequency_hz, [omega / (2 * np.pi)], rtol=1e-12, atol=0)
    np.testing.assert_allclose(model.damped_frequency_hz,
                               [omega * np.sqrt(1 - zeta**2) / (2 * np.pi)], rtol=1e-12, atol=0)
    # the outputs read the block's slide: y = C x for x = [z, 0] is the body motion of N z
    dx = model.C[model.output_names.index("block.dx"), 0]
    np.testing.assert_allclose(abs(dx), 1.0, rtol=1e-12, atol=0)  # N's column is a unit x


def test_four_bar_frequency_matches_finite_differences_of_the_dynamics():
    functions, result = modal(HANGING_FOUR_BAR)
    model = result.linear_model
    assert len(model.frequency_hz) == 1  # 1 DOF (three of the 4 x 5 revolute rows redundant)
    q_star = model.q
    direction = model.basis[:, 0]
    eps = 1e-5
    positions, accelerations = [], []
    for sign in (1.0, -1.0):
        q = assembly.newton(functions, 0.0, q_star + sign * eps * direction)
        q_ddot, _ = assembly.solve_dynamic_accelerations(functions, 0.0, q, np.zeros_like(q))
        positions.append(direction @ q)
        accelerations.append(direction @ q_ddot)
    omega2 = -(accelerations[0] - accelerations[1]) / (positions[0] - positions[1])
    # central differences with eps = 1e-5: truncation ~eps^2 relative, roundoff of the Newton
    # projection (1e-12 of 1e-5) ~1e-7 at worst; measured 4e-11: rtol 1e-7
    np.testing.assert_allclose(model.frequency_hz, [np.sqrt(omega2) / (2 * np.pi)], rtol=1e-7,
                               atol=0)


def test_linearization_matches_finite_differences_with_spring():
    # K from AD against a central difference along the manifold of the unbalanced force
    # R = Q - Phi_q^T lam(q) (lam least squares, so R = (I - Pi) Q, Pi onto Phi_q's row space):
    # at an equilibrium d(N^T R)/ds = N^T dR/dq N = -K, the constraint-curvature term included
    functions = compiled(RSDA_PENDULUM, theta0=1.2)
    equilibrium = statics.solve(functions)
    system = equilibrium.system
    direction = system.basis[:, 0]
    eps = 1e-6
    forces = []
    for sign in (1.0, -1.0):
        q = assembly.newton(functions, 0.0, equilibrium.q + sign * eps * direction)
        forces.append(direction @ statics.reduced_system(functions, 0.0, q).residual)
    stiffness = -(forces[0] - forces[1]) / (2 * eps)
    # central difference: ~1e-12 / 1e-6 roundoff on O(10) N forces: rtol 1e-6
    np.testing.assert_allclose(system.stiffness[0, 0], stiffness, rtol=1e-6, atol=0)


def test_cli_modal_writes_modes_and_linear_model(tmp_path):
    from casmech.cli import main
    from casmech.io.csv import read_csv

    assert main(["run", str(MODELS / "double_pendulum.yaml"), "--analysis", "modal",
                 "--out", str(tmp_path)]) == 0
    names, values = read_csv(tmp_path / "modes.csv")
    assert names[:5] == ["mode", "frequency_hz", "damping_ratio", "eigenvalue_real",
                         "eigenvalue_imag"]
    assert values.shape == (2, len(names))
    data = np.load(tmp_path / "linear_model.npz")
    assert data["A"].shape == (4, 4) and data["C"].shape == (12, 4)
    assert list(data["state_names"]) == ["z1", "z2", "z1_dot", "z2_dot"]
    # the eigenvalues of the saved A are the modes listed (conjugates once): rtol 1e-12
    eigenvalues = np.linalg.eigvals(data["A"])
    upper = np.sort(eigenvalues[eigenvalues.imag > 0].imag)
    np.testing.assert_allclose(upper, values[:, 4], rtol=1e-12, atol=0)
    # the equilibrium row is in results.csv
    names, rows = read_csv(tmp_path / "results.csv")
    assert rows.shape[0] == 1


def test_modal_row_is_the_statics_row():
    functions = compiled(RSDA_PENDULUM, theta0=1.0)
    static = row(functions, casmech.analyze(functions, "statics"))
    modes = row(functions, casmech.analyze(functions, "modal"))
    assert static == modes


def test_cart_pole_free_cart_mode_and_coupled_pendulum_frequency():
    model = casmech.load(MODELS / "cart_pole.yaml")  # pole released near upright: it hangs
    functions = casmech.compile(model)
    result = casmech.analyze(functions, "modal")
    big, m, length, w = (model.parameters[n] for n in ("m_cart", "m_pole", "L", "w"))
    arm, inertia = length / 2, m * (length**2 + w**2) / 12
    # x (cart) and theta (pole from hanging): mass [[M + m, m l], [m l, I + m l^2]],
    # stiffness diag(0, m g l): a rigid mode of the cart and one pendulum mode
    omega2 = m * G * arm * (big + m) / ((big + m) * (inertia + m * arm**2) - (m * arm)**2)
    model_ = result.linear_model
    # two DOF, two modes: 0 Hz exactly (the cart's zero stiffness) and the coupled frequency
    # (rtol 1e-10: a 4 x 4 eigenproblem at an equilibrium converged to roundoff)
    assert model_.frequency_hz[0] == 0.0
    np.testing.assert_allclose(model_.frequency_hz[1:], [np.sqrt(omega2) / (2 * np.pi)],
                               rtol=1e-10, atol=0)
    # the zero mode moves the whole mechanism along x only (the cart's rail)
    shape = model_.mode_shapes[0]
    np.testing.assert_allclose(shape[:, 0], 1.0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(shape[:, 1:], 0.0, rtol=0, atol=1e-10)


def test_motor_input_static_gain_is_one_over_m_g_l():
    # an effort motor (torque 0 by default) on the hanging rod's pivot is the input
    text = HANGING_ROD.replace("axis: [0, 1, 0]}", "axis: [0, 1, 0],\n     motor: {torque: \"0\"}}")
    functions, result = modal(text)
    model = result.linear_model
    assert model.input_names == ["pivot.torque"]
    assert model.B.shape == (2, 1) and model.D.shape == (6, 1)
    # steady state y = -C A^-1 B u: the rod turns about y by u / (m g l), l = L / 2
    gain = -model.C @ np.linalg.solve(model.A, model.B)
    m, length = 1.5, 0.8
    # a 2 x 2 solve at an equilibrium converged to roundoff: rtol 1e-10
    np.testing.assert_allclose(gain[model.output_names.index("rod.ry"), 0],
                               1 / (m * G * length / 2), rtol=1e-10, atol=0)
    # the rod's CM moves along x by l times that rotation (hanging along -z, turning about +y)
    np.testing.assert_allclose(gain[model.output_names.index("rod.dx"), 0],
                               -(length / 2) / (m * G * length / 2), rtol=1e-10, atol=0)


def test_triple_pendulum_frequencies_and_mode_shapes():
    from tests.helpers import gallery_closed_forms as cf

    model = casmech.load(MODELS / "triple_pendulum.yaml")  # equilibrium found from (60, 30, 0)
    functions = casmech.compile(model)
    result = casmech.analyze(functions, "modal").linear_model
    rods = ("rod1", "rod2", "rod3")
    bodies = {b.name: b for b in model.bodies}
    lengths = [model.parameters[f"L{k}"] for k in (1, 2, 3)]
    omegas, shapes = cf.normal_modes(*cf.chain_pendulum(
        lengths, [bodies[r].mass for r in rods], [bodies[r].inertia[1, 1] for r in rods], G))
    # rtol 1e-10: a 6 x 6 eigenproblem at an equilibrium converged to roundoff
    np.testing.assert_allclose(result.frequency_hz, omegas / (2 * np.pi), rtol=1e-10, atol=0)
    # each mode's rod rotations about y, scaled like the closed form's (largest entry 1): the
    # eigenvectors of distinct eigenvalues agree to ~1e-12; atol 1e-9
    for mode in range(3):
        turns = result.mode_shapes[mode, :, 4].real
        np.testing.assert_allclose(turns / turns[np.argmax(np.abs(turns))], shapes[:, mode],
                                   rtol=0, atol=1e-9)


def test_state_space_frequency_response_is_the_compound_pendulum():
    """python-control's StateSpace of the rod driven at its pivot: the response of the rod's
    rotation to the torque at omega is 1 / (m g l - J omega^2) (J about the pivot), names kept
    ('.' as '_')."""
    import control

    text = HANGING_ROD.replace("axis: [0, 1, 0]}", "axis: [0, 1, 0],\n     motor: {torque: \"0\"}}")
    _, result = modal(text)
    system = result.linear_model.state_space()
    assert isinstance(system, control.StateSpace)
    assert system.input_labels == ["pivot_torque"] and system.state_labels == ["z1", "z1_dot"]
    m, length, w = 1.5, 0.8, 0.03
    arm = length / 2
    inertia = m * (length**2 + w**2) / 12 + m * arm**2
    output = system.output_labels.index("rod_ry")
    for omega in (0.5, 2.0, 11.0):
        response = system(1j * omega)[output, 0]
        # a 2 x 2 linear model at an equilibrium converged to roundoff: rtol 1e-9
        np.testing.assert_allclose(response.real, 1 / (m * G * arm - inertia * omega**2),
                                   rtol=1e-9, atol=0)
        assert abs(response.imag) <= 1e-12
