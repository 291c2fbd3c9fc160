"""The bushing (casmech/elements/forces/bushing.py) against closed forms, finite differences
and a fixed joint.

Every model is a YAML text run through the public API; expectations are closed forms of the
linear oscillator, numpy's own rotation-vector arithmetic, or a second formulation (fixed joint).
"""

from __future__ import annotations

import numpy as np
import pytest

import casmech
import casmech.errors
from casmech.equations.functions import SystemFunctions
from tests.conftest import Table
from tests.helpers.equations import rotation

MASS = """
casmech: 1
name: bushing_test
parameters: {{m: 2.0, k1: 800.0, k2: 450.0, k3: 1250.0, kr: 30.0}}
gravity: [0, 0, {g}]
bodies:
  - name: block
    mass: m
    inertia: [0.1, 0.2, 0.25]
    position: [0.3, -0.2, 0.1]
    velocity: {v}
    angular_velocity: {w}
forces:
  - name: mount
    type: bushing
    body_i: ground
    body_j: block
    at: [0.3, -0.2, 0.1]
    orientation: {orientation}
    stiffness: [k1, k2, k3]
    damping: {c}
    rotational_stiffness: [kr, kr, kr]
analysis: {{type: dynamics, t_end: 1.0, output_step: 0.01, rtol: 1.0e-10, atol: 1.0e-12}}
"""
M, K, KR = 2.0, np.array([800.0, 450.0, 1250.0]), 30.0
TURN = np.pi / 6  # the bushing frame is turned about global z by this angle
TURNED = f"{{axis_angle: {{axis: [0, 0, 1], angle: {TURN}}}}}"
FRAME = rotation(np.r_[np.cos(TURN / 2), 0, 0, np.sin(TURN / 2)])  # its axes, global


def run(text: str, t_end: float, step: float = 0.01) -> Table:
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions, "dynamics", t_end=t_end, output_step=step)
    return Table(*casmech.results_table(functions, result))


def mass_model(v=(0, 0, 0), w=(0, 0, 0), g=0.0, c=(0, 0, 0), orientation=TURNED) -> str:
    return MASS.format(v=_vector(v), w=_vector(w), g=g, c=_vector(c), orientation=orientation)


def _vector(values) -> str:
    return "[" + ", ".join(format(float(x), ".17g") for x in values) + "]"


def positions(table: Table, body: str) -> np.ndarray:
    return np.column_stack([table[f"{body}.{a}"] for a in "xyz"])


def test_translational_natural_frequencies_are_sqrt_k_over_m():
    """Started at the rest pose with velocity u along each bushing axis (turned 30 deg about z),
    the block moves along each axis as (u/omega) sin(omega t), omega = sqrt(k_axis/m)."""
    u = np.array([0.05, -0.03, 0.02])  # speeds along the bushing axes
    table = run(mass_model(v=FRAME @ u), t_end=0.6)
    local = (positions(table, "block") - [0.3, -0.2, 0.1]) @ FRAME  # bushing-axis components
    omega = np.sqrt(K / M)
    exact = u / omega * np.sin(np.outer(table["t"], omega))
    # IDAS at rtol 1e-10: measured max 1.1e-10 m on amplitudes ~1e-3 m
    np.testing.assert_allclose(local, exact, rtol=0, atol=1e-9)
    assert np.max(np.abs(local[:, 0] - exact[:, 1])) > 1e-4  # the axes really differ


def test_rotational_frequency_is_sqrt_kr_over_j_even_at_one_radian():
    """Isotropic rotational stiffness: the torque is -kr theta with theta the rotation vector,
    exactly linear, so a spin w0 about the principal z axis gives angle = (w0/omega) sin(omega t)
    with omega = sqrt(kr/Jz), here with a 1 rad amplitude (a sin- or tan-type angle measure
    would show the difference)."""
    omega = np.sqrt(KR / 0.25)
    table = run(mass_model(w=(0, 0, omega)), t_end=0.8)
    angle = 2 * np.arctan2(table["block.e3"], table["block.e0"])
    # IDAS at rtol 1e-10: measured 3.5e-9 rad on a 1 rad amplitude
    np.testing.assert_allclose(angle, np.sin(omega * table["t"]), rtol=0, atol=2e-8)
    wrong = 2 * np.sin(np.sin(omega * table["t"]) / 2)  # the 2 sin(theta/2) measure
    assert np.max(np.abs(wrong - angle)) > 1e-2


def test_static_deflection_under_gravity_is_m_g_over_k():
    """Released at rest under gravity: z(t) - z0 = -(m g/k3)(1 - cos(omega t)) about the
    static deflection m g / k3 (bushing frame = global axes)."""
    table = run(mass_model(g=-9.81, orientation="null"), t_end=0.5)
    omega = np.sqrt(K[2] / M)
    static = M * 9.81 / K[2]
    exact = -static * (1 - np.cos(omega * table["t"]))
    # IDAS at rtol 1e-10: measured 2.0e-9 m on a 0.016 m static deflection
    np.testing.assert_allclose(table["block.z"] - 0.1, exact, rtol=0, atol=1e-8)
    np.testing.assert_allclose(positions(table, "block")[:, :2], [[0.3, -0.2]] * len(exact),
                               rtol=0, atol=1e-12)  # nothing pulls sideways: exactly still


def test_damping_decays_at_c_over_2m():
    """Underdamped: x = (u/omega_d) exp(-c t/(2m)) sin(omega_d t), omega_d^2 = k/m - (c/2m)^2."""
    c, u = 8.0, 0.05
    table = run(mass_model(v=FRAME @ [u, 0, 0], c=(c, c, c)), t_end=0.8)
    x = (positions(table, "block") - [0.3, -0.2, 0.1]) @ FRAME[:, 0]
    sigma = c / (2 * M)
    omega_d = np.sqrt(K[0] / M - sigma**2)
    t = table["t"]
    exact = u / omega_d * np.exp(-sigma * t) * np.sin(omega_d * t)
    # IDAS at rtol 1e-10: measured 2.2e-10 m on a 2.5e-3 m amplitude
    np.testing.assert_allclose(x, exact, rtol=0, atol=2e-9)
    undamped = u / np.sqrt(K[0] / M) * np.sin(np.sqrt(K[0] / M) * t)
    assert np.max(np.abs(undamped - exact)) > 1e-4


# ------------------------------------------------------------------ force = -grad(potential)
PAIR = """
casmech: 1
name: bushing_pair
gravity: [0, 0, 0]
bodies:
  - {name: a, mass: 1.5, inertia: [0.1, 0.12, 0.15], position: [0, 0, 0],
     orientation: {axis_angle: {axis: [1, 2, 3], angle: 0.4}},
     velocity: [0.2, -0.1, 0.3], angular_velocity: [0.5, -0.7, 0.2]}
  - {name: b, mass: 0.8, inertia: [0.05, 0.06, 0.07], position: [0.4, 0.1, -0.2],
     orientation: {axis_angle: {axis: [-1, 1, 2], angle: 1.1}},
     velocity: [-0.3, 0.4, 0.1], angular_velocity: [1.5, 0.3, -2.0]}
forces:
  - {name: link, type: bushing, body_i: a, body_j: b, at: [0.25, 0.05, -0.1],
     orientation: {x_axis: [1, 1, 0], z_axis: [0, 0, 1]},
     stiffness: [300, 500, 700], rotational_stiffness: [20, 35, 50],
     preload_force: [1, -2, 3], preload_torque: [0.2, 0.1, -0.3]{damping}}
"""


def _pair(damping: str = "") -> SystemFunctions:
    return casmech.compile(casmech.loads(PAIR.replace("{damping}", damping)))


def test_force_is_minus_the_gradient_of_the_potential_energy(rng):
    """generalized_forces(t, q, 0) (no gravity, no velocity) = -dV/dq by central differences of
    the `energy` function's potential, at random (also non-unit) q."""
    functions = _pair()
    q = rng.normal(size=14) * 0.5
    q[6:] = q[6:] + np.r_[1.0, 0, 0, 0, 1.0, 0, 0, 0]
    zero = np.zeros(14)
    force = functions.vector("generalized_forces", 0.0, q, zero)

    def potential(x):
        return float(functions.evaluate("energy", 0.0, x, zero)[1].item())

    h = 1e-6
    gradient = np.array([(potential(q + h * e) - potential(q - h * e)) / (2 * h)
                         for e in np.eye(14)])
    # central differences at h = 1e-6: measured 1.2e-6 on entries up to 6.6e3 (random poses
    # deflect the bushing far), i.e. 2e-10 relative
    np.testing.assert_allclose(force, -gradient, rtol=1e-7, atol=1e-5)


def _rotation_vector(a: np.ndarray) -> np.ndarray:
    """log of a rotation matrix (numpy, angle < pi)."""
    angle = np.arccos(np.clip((np.trace(a) - 1) / 2, -1, 1))
    vee = np.array([a[2, 1] - a[1, 2], a[0, 2] - a[2, 0], a[1, 0] - a[0, 1]]) / 2
    return vee * (angle / np.sin(angle) if angle > 1e-12 else 1.0)


def test_force_on_j_is_minus_k_d_plus_preload_in_the_i_frame(rng):
    """The r_j rows of the generalized force are the force on J: A_I (-K d + F0), with
    d = A_I^T (P_J - P_I) computed here in numpy, the I frame carried by body_i from the pose
    in the file."""
    functions = _pair()
    model = casmech.loads(PAIR.replace("{damping}", ""))
    a0, b0 = (rotation(body.euler_parameters) for body in model.bodies)
    r0 = [body.position for body in model.bodies]
    frame = rotation(model.forces[0].vectors["orientation"])
    at = np.array([0.25, 0.05, -0.1])
    s_i, s_j = a0.T @ (at - r0[0]), b0.T @ (at - r0[1])
    for _ in range(3):
        p = [rng.normal(size=4) for _ in range(2)]
        p = [x / np.linalg.norm(x) for x in p]
        r = [rng.normal(size=3) * 0.3 for _ in range(2)]
        q = np.r_[r[0], r[1], p[0], p[1]]
        a, b = rotation(p[0]), rotation(p[1])
        marker_i = a @ a0.T @ frame  # the I frame's axes, global
        d = marker_i.T @ (r[1] + b @ s_j - r[0] - a @ s_i)
        force = functions.vector("generalized_forces", 0.0, q, np.zeros(14))
        expected = marker_i @ (-np.array([300, 500, 700]) * d + [1, -2, 3])
        # the same arithmetic in two implementations: measured 2.3e-13 N on ~1e2 N
        np.testing.assert_allclose(force[3:6], expected, rtol=1e-10, atol=1e-10)


def test_free_pair_conserves_momentum_and_energy():
    """Two free bodies on a bushing (no damping, preloads on): total linear and angular
    momentum and the energy stay constant, so the force and torque on I are the opposite of
    those on J plus the moment of the force's arm."""
    functions = _pair()
    result = casmech.analyze(functions, "dynamics", t_end=0.5, output_step=0.01,
                             rtol=1e-10, atol=1e-12)
    table = Table(*casmech.results_table(functions, result))
    model = casmech.loads(PAIR.replace("{damping}", ""))
    linear, angular = 0.0, 0.0
    for body in model.bodies:
        r, v = positions(table, body.name), np.column_stack(
            [table[f"{body.name}.v{a}"] for a in "xyz"])
        w = np.column_stack([table[f"{body.name}.w{a}"] for a in "xyz"])
        p = np.column_stack([table[f"{body.name}.e{k}"] for k in range(4)])
        spin = np.array([rotation(pk) @ body.inertia @ rotation(pk).T @ wk
                         for pk, wk in zip(p, w, strict=True)])
        linear = linear + body.mass * v
        angular = angular + body.mass * np.cross(r, v) + spin
    # IDAS at rtol 1e-10 over 0.5 s: measured drift 2e-15 (linear, ~0.5 N s), 2.6e-10 (angular,
    # ~0.2 N m s), 1.9e-8 J (energy 0.43 J)
    np.testing.assert_allclose(linear, linear[:1].repeat(len(linear), 0), rtol=0, atol=1e-9)
    np.testing.assert_allclose(angular, angular[:1].repeat(len(angular), 0), rtol=0, atol=3e-9)
    np.testing.assert_allclose(table["energy"], table["energy"][0], rtol=0, atol=1e-7)
    assert np.ptp(positions(table, "b")[:, 0] - positions(table, "a")[:, 0]) > 1e-3


def test_damping_dissipates_and_never_adds_energy():
    functions = _pair(", damping: [5, 5, 5], rotational_damping: [0.2, 0.3, 0.4]")
    result = casmech.analyze(functions, "dynamics", t_end=0.5, output_step=0.01)
    energy = Table(*casmech.results_table(functions, result))["energy"]
    # Rayleigh dissipation: dE/dt = -s_dot^T C s_dot <= 0; IDAS noise at rtol 1e-8 ~1e-9 J
    assert np.all(np.diff(energy) < 1e-8)
    assert energy[-1] < energy[0] - 1e-2


# ---------------------------------------------------------------- stiff bushing = fixed joint
ARM = """
casmech: 1
name: arm_with_welded_block
gravity: [0, 0, -9.81]
bodies:
  - {name: arm, mass: 1.0, inertia: [0.01, 0.09, 0.09], position: [0.5, 0, 0]}
  - {name: block, mass: 2.0, inertia: [0.02, 0.03, 0.04], position: [1.1, 0, 0.05]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: arm, at: [0, 0, 0], axis: [0, 1, 0]}
"""
WELD = "  - {name: weld, type: fixed, body_i: arm, body_j: block, at: [1.0, 0, 0]}\n"
BUSHING = """forces:
  - {name: weld, type: bushing, body_i: arm, body_j: block, at: [1.0, 0, 0],
     stiffness: [1.0e6, 1.0e6, 1.0e6], damping: [2800, 2800, 2800],
     rotational_stiffness: [1.0e5, 1.0e5, 1.0e5], rotational_damping: [150, 150, 150]}
"""


def _bushing_reaction(table: Table, model) -> tuple[np.ndarray, np.ndarray]:
    """Force and torque (about the arm's copy of `at`) the stiff bushing exerts on the block,
    from the results columns, in numpy: -K d - C d_dot and -Kt theta - Ct theta_dot."""
    at = np.array([1.0, 0, 0])
    bodies = {b.name: b for b in model.bodies}
    s = {name: rotation(b.euler_parameters).T @ (at - b.position) for name, b in bodies.items()}
    forces, torques = [], []
    for n in range(len(table["t"])):
        state = {}
        for name in bodies:
            p = np.array([table[f"{name}.e{k}"][n] for k in range(4)])
            r, v, w = (np.array([table[f"{name}.{x}{a}"][n] for a in "xyz"])
                       for x in ("", "v", "w"))
            arm = rotation(p) @ s[name]
            state[name] = (rotation(p), r + arm, v + np.cross(w, arm), w)
        (a, p_i, v_i, w_i), (b, p_j, v_j, w_j) = state["arm"], state["block"]
        d_dot = a.T @ (v_j - v_i) - np.cross(a.T @ w_i, a.T @ (p_j - p_i))
        force = a @ (-1.0e6 * (a.T @ (p_j - p_i)) - 2800 * d_dot)
        theta = _rotation_vector(a.T @ b)  # both start with the global axes
        torque = a @ (-1.0e5 * theta - 150 * (a.T @ (w_j - w_i))) + np.cross(p_j - p_i, force)
        forces.append(force)
        torques.append(torque)
    return np.array(forces), np.array(torques)


def test_stiff_bushing_carries_the_fixed_joints_reaction():
    """An arm swinging under gravity with a block welded to its tip: the stiff bushing's force
    and torque on the block (past its ~3 ms start-up transient) equal the fixed joint's reaction
    columns of the same mechanism."""
    fixed = run(ARM + WELD, t_end=0.4, step=0.02)
    model = casmech.loads(ARM + BUSHING)
    soft = run(ARM + BUSHING, t_end=0.4, step=0.02)
    force, torque = _bushing_reaction(soft, model)
    late = fixed["t"] >= 0.04
    expected_f = np.column_stack([fixed[f"weld.f{a}"] for a in "xyz"])
    expected_t = np.column_stack([fixed[f"weld.t{a}"] for a in "xyz"])
    # O(m g / k) = 2e-5 m deflections change the motion slightly: measured 2.3e-3 N on 32 N,
    # 1.6e-4 N m on 1.6 N m (from t = 0.02 s on)
    np.testing.assert_allclose(force[late], expected_f[late], rtol=0, atol=1e-2)
    np.testing.assert_allclose(torque[late], expected_t[late], rtol=0, atol=1e-3)
    assert np.max(np.abs(expected_f[late])) > 10  # a real load, not zeros
    np.testing.assert_allclose(positions(soft, "block"), positions(fixed, "block"),
                               rtol=0, atol=1e-4)  # measured 4.7e-5 m (sag ~ m g/k, tilt)


@pytest.mark.parametrize("key", ["stiffness", "rotational_damping"])
def test_negative_coefficients_are_located_errors(key):
    text = mass_model().replace("damping: [0, 0, 0]", f"{key}: [1, -2, 3]", 1)
    text = text.replace("    stiffness: [k1, k2, k3]\n", "") if key == "stiffness" else text
    with pytest.raises(casmech.errors.ModelError) as caught:
        casmech.loads(text)
    (diagnostic,) = caught.value.diagnostics
    line = next(n for n, row in enumerate(text.splitlines(), 1) if row.strip().startswith(key))
    assert (diagnostic.code, diagnostic.source.line) == ("E103", line)
    assert "must not be negative" in diagnostic.message


def test_sensitivity_to_the_stiffness_is_the_closed_forms_derivative():
    """d z(t)/d k3 by IDAS forward sensitivities equals the derivative of the released-at-rest
    closed form z - z0 = -(m g/k)(1 - cos(sqrt(k/m) t))."""
    from casmech.optimal.sensitivity import sensitivity

    model = casmech.loads(mass_model(g=-9.81, orientation="null"))
    times = np.array([0.05, 0.12, 0.3])
    result = sensitivity(model, ["k3", "k1"], ["block.z"], list(times), mode="forward")
    k, g = K[2], 9.81
    omega = np.sqrt(k / M)
    exact = (M * g / k**2 * (1 - np.cos(omega * times))
             - M * g / k * np.sin(omega * times) * times / (2 * np.sqrt(k * M)))
    jacobian = np.asarray(result.jacobian)[:, 0, :]
    # IDAS sensitivities at the model's rtol 1e-10: measured 5.9e-13 on entries up to 3.6e-5
    np.testing.assert_allclose(jacobian[:, 0], exact, rtol=1e-6, atol=1e-11)
    np.testing.assert_allclose(jacobian[:, 1], 0.0, rtol=0, atol=1e-11)  # k1 acts along x
