"""The model gallery: every model in models/ (and the IFToMM ones in models/validation/) loads,
checks with the DOF its header states, and runs its own analysis for a short time with the
constraints kept; each mechanism that has one is checked against a closed form or an invariant
computed here in numpy (tests/helpers/gallery_closed_forms.py), never against casmech's own
numbers."""

from __future__ import annotations

import re

import numpy as np
import pytest

import casmech
from tests.conftest import MODELS, Table
from tests.helpers import gallery_closed_forms as cf

GALLERY = sorted(MODELS.glob("*.yaml")) + sorted((MODELS / "validation").glob("iftomm_*.yaml"))
SMOKE_T_END = 0.2  # simulated seconds per model in the smoke run
# dynamics projects when |Phi| > 1e-9; Newton in kinematics converges to ~1e-12: 1e-8 is margin
PHI_LIMIT = 1e-8


def run(name: str, overrides: dict | None = None, **settings):
    model = casmech.load(MODELS / f"{name}.yaml", {k: format(float(v), ".17g")
                                                for k, v in (overrides or {}).items()})
    functions = casmech.compile(model)
    result = casmech.analyze(functions, **settings)
    return model, functions, Table(*casmech.results_table(functions, result))


def header_dof(text: str) -> int:
    """The DOF the header comment states: 'DOF: ... = N' (last '=', parentheses ignored)."""
    header = " ".join(line.lstrip("# ") for line in text.splitlines() if line.startswith("#"))
    match = re.search(r"DOF:\s*(.*?)(?:\.\s|\.$|$)", header)
    assert match, "the header comment must state the DOF as 'DOF: ... = N'"
    clause = match.group(1)
    clause = re.sub(r"\([^)]*\)", "", clause)
    return int(re.search(r"\d+", clause.rsplit("=", 1)[-1]).group())


# the gallery models added for issue 5, and all the mechanisms it asks for
NEW = {"double_pendulum", "triple_pendulum", "heavy_top", "cardan_shaft", "flyball_governor",
       "robot_arm_3r", "cart_pole", "bricard", "scotch_yoke", "spatial_rsur"}
WANTED = NEW | {"iftomm_a01_pendulum", "iftomm_a02_four_bar_N2", "slider_crank", "four_bar"}


def test_gallery_has_the_mechanisms_the_issue_lists():
    assert WANTED <= {path.stem for path in GALLERY}


@pytest.mark.parametrize("path", [p for p in GALLERY if p.stem in WANTED],
                         ids=[p.stem for p in GALLERY if p.stem in WANTED])
def test_gallery_model_draws_every_body_and_documents_itself(path):
    model = casmech.load(path)
    assert all(body.geometry for body in model.bodies)
    header = "".join(line for line in model.text.splitlines() if line.startswith("#"))
    assert "DOF:" in header
    if path.stem in NEW:
        assert "Source" in header and "Default analysis" in header


@pytest.mark.parametrize("path", GALLERY, ids=[p.stem for p in GALLERY])
def test_model_checks_and_runs(path):
    model = casmech.load(path)
    functions = casmech.compile(model)
    report, assembled = casmech.check(functions)
    assert assembled
    assert report.dof == header_dof(model.text)
    settings = model.analysis
    result = casmech.analyze(functions, t_end=min(SMOKE_T_END, settings.t_end),
                             output_step=min(0.02, settings.output_step))
    names, values = casmech.results_table(functions, result)
    assert values[-1, 0] == pytest.approx(min(SMOKE_T_END, settings.t_end), abs=1e-12)
    assert np.all(np.isfinite(values))
    assert np.max(values[:, names.index("constraint_violation")]) < PHI_LIMIT


# -------------------------------------------------------------------------------- pendulums
PENDULUMS = {"double_pendulum": ("rod1", "rod2"), "triple_pendulum": ("rod1", "rod2", "rod3")}


@pytest.mark.parametrize("name", sorted(PENDULUMS))
def test_pendulum_energy_is_conserved(name):
    model, _, table = run(name, t_end=0.3, output_step=0.01)
    energy = cf.mechanical_energy(model, table)
    # IDAS at rtol 1e-8 plus projections: measured drift 2.8e-6 J (double), 1.0e-6 J (triple)
    # over 0.5 s of the large-angle motion, on |E| ~ 5 and 11 J
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=3e-5)


@pytest.mark.parametrize("name", sorted(PENDULUMS))
def test_pendulum_small_oscillation_is_the_sum_of_its_normal_modes(name):
    """Released at rest from eps * (sum of the mode shapes v_k), every angle follows
    eps * sum_k v_k cos(omega_k t), omega_k from the linearised chain M theta'' + K theta = 0."""
    rods = PENDULUMS[name]
    model = casmech.load(MODELS / f"{name}.yaml")
    lengths = [model.parameters[f"L{k + 1}"] for k in range(len(rods))]
    bodies = {b.name: b for b in model.bodies}
    masses = [bodies[rod].mass for rod in rods]
    inertias = [bodies[rod].inertia[1, 1] for rod in rods]  # about y, the hinge direction
    omegas, shapes = cf.normal_modes(*cf.chain_pendulum(lengths, masses, inertias, 9.81))
    eps = 1e-3
    start = shapes.sum(1) * eps
    _, _, table = run(name, {f"theta{k + 1}": start[k] for k in range(len(rods))}, t_end=0.3,
                      output_step=0.01, rtol=1e-10, atol=1e-12)
    exact = eps * np.cos(np.outer(table["t"], omegas)) @ shapes.T
    angles = np.column_stack([cf.rotation_about_y(table, rod) for rod in rods])
    # nonlinear terms O(eps^3) and IDAS at rtol 1e-10: measured up to 9e-9 rad (one mode at a
    # time, 0.4 s); 5e-8 rad is far below the 1e-5 rad a 1 % error in any omega_k gives
    np.testing.assert_allclose(angles, exact, rtol=0, atol=5e-8)
    wrong = eps * np.cos(np.outer(table["t"], omegas * 1.01)) @ shapes.T
    assert np.max(np.abs(wrong - exact)) > 100 * 5e-8


# -------------------------------------------------------------------------------- heavy top
@pytest.fixture(scope="module")
def heavy_top():
    return run("heavy_top", t_end=0.5, output_step=0.01)


def test_heavy_top_conserves_energy_and_vertical_momentum(heavy_top):
    model, _, table = heavy_top
    energy = cf.mechanical_energy(model, table)
    momentum_z = cf.angular_momentum(model, table)[:, 2]
    # r-omega form at rtol 1e-8: measured energy drift 1.6e-9 J on E = 25.9 J (spin 100 rad/s)
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-7)
    # L_z = 0.44 kg m^2/s: measured drift 8e-10
    np.testing.assert_allclose(momentum_z, momentum_z[0], rtol=0, atol=1e-8)


def test_heavy_top_precesses_steadily_at_the_closed_form_rate(heavy_top):
    model, _, table = heavy_top
    p = model.parameters
    axis = cf.body_state(table, "top")["A"][:, :, 2]  # the symmetry axis, global
    i1_pivot = p["m"] * (3 * p["R"]**2 + p["h"]**2) / 12 + p["m"] * p["l"]**2
    rate = cf.steady_precession_rate(p["m"], 9.81, p["l"], i1_pivot, p["m"] * p["R"]**2 / 2,
                                     p["omega3"], p["theta0"])
    # the gyroscopic approximation m g l / (I3 omega3) is 4.5 % below the exact slow root here
    assert rate == pytest.approx(p["m"] * 9.81 * p["l"] / (p["m"] * p["R"]**2 / 2
                                                           * p["omega3"]), rel=0.05)
    # tilt: measured constant to 4e-9 rad; started with Omega 1 % off the relation, the axis
    # nutates by 5.6e-4 rad within 0.5 s
    np.testing.assert_allclose(np.arccos(axis[:, 2]), p["theta0"], rtol=0, atol=1e-7)
    heading = np.unwrap(np.arctan2(axis[:, 1], axis[:, 0]))
    # precession angle Omega t reaches 1 rad in 0.5 s, measured error 1.5e-8 rad; a 1 % error
    # in the rate would be 1e-2 rad
    np.testing.assert_allclose(heading, rate * table["t"], rtol=0, atol=1e-6)


# -------------------------------------------------------------------------------- cart-pole
def test_cart_pole_keeps_horizontal_momentum_and_centre_of_mass():
    model, _, table = run("cart_pole", t_end=0.3, output_step=0.01)
    momentum = cf.linear_momentum(model, table)
    total = sum(b.mass for b in model.bodies)
    centre_x = sum(b.mass * table[f"{b.name}.x"] for b in model.bodies) / total
    # released at rest: P_x = 0; measured |P_x| <= 2.5e-9 kg m/s (IDAS rtol 1e-8, m v ~ 0.1)
    np.testing.assert_allclose(momentum[:, 0], 0.0, rtol=0, atol=1e-7)
    # the CM x stays put (measured 6e-10 m) while the cart itself moves (checked below)
    np.testing.assert_allclose(centre_x, centre_x[0], rtol=0, atol=1e-8)
    assert np.ptp(table["cart.x"]) > 3e-3
    energy = cf.mechanical_energy(model, table)
    # no damping, no work by the (zero) push: measured drift 6e-8 J on E ~ 1 J
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-6)


# -------------------------------------------------------------------------------- governor
def governor_data(model):
    p = model.parameters
    return 9.81, p["omega"], p["d"], p["l"], p["m"], p["Ib"], p["H"]


def arm_angle(table, data):
    _, _, offset, _, _, _, height = data
    radius = np.hypot(table["arm_a.x"], table["arm_a.y"])
    return np.arctan2(radius - offset, height - table["arm_a.z"])


def test_governor_stays_at_the_closed_form_steady_angle():
    data = governor_data(casmech.load(MODELS / "flyball_governor.yaml"))
    g, omega, offset, arm, *_ = data
    steady = cf.governor_angle(g, omega, offset, arm)
    _, _, table = run("flyball_governor", {"alpha0": steady}, t_end=0.3, output_step=0.01)
    # an equilibrium of the rotating arm: measured constant to 2.3e-7 rad over 0.5 s; started
    # 0.05 rad off it, the arm moves by 0.06 rad in 0.5 s (see also the next test)
    np.testing.assert_allclose(arm_angle(table, data), steady, rtol=0, atol=1e-6)


def test_governor_arm_acceleration_off_steady_state():
    """Started at alpha != alpha*, the arm's initial angular acceleration is
    -U'(alpha) / (I_ball + m l^2) (effective potential in the spindle frame)."""
    model = casmech.load(MODELS / "flyball_governor.yaml")
    g, omega, offset, arm, mass, inertia, _ = governor_data(model)
    alpha = cf.governor_angle(g, omega, offset, arm) + 0.1
    _, _, table = run("flyball_governor", {"alpha0": alpha}, analysis="assembly")
    expected = -mass * cf.governor_potential_slope(alpha, g, omega, offset, arm) / (
        inertia + mass * arm**2)
    # arm_a opens about -y at t = 0: its alpha_y is -alpha''; the solve is direct (no
    # integration): 1e-9 relative, 1e-9 absolute on ~10 rad/s^2
    np.testing.assert_allclose(-table["arm_a.alphay"][0], expected, rtol=1e-9, atol=1e-9)
    assert abs(expected) > 1.0


# -------------------------------------------------------------------------- Cardan, linkages
def test_cardan_output_speed_matches_hooke_joint_formula():
    model, _, table = run("cardan_shaft", t_end=1.0, output_step=0.01)
    p = model.parameters
    axis = np.array([np.cos(p["b"]), np.sin(p["b"]), 0.0])
    output = np.column_stack([table[f"output_shaft.w{c}"] for c in "xyz"]) @ axis
    expected = cf.cardan_output_speed(p["omega"], p["b"], p["omega"] * table["t"])
    # kinematics by Newton + linear solves: measured max error 1e-14 rad/s on ~7 rad/s
    np.testing.assert_allclose(output, expected, rtol=0, atol=1e-9)
    assert np.ptp(output) > 0.5  # the speed really fluctuates (cos b to 1/cos b)


def test_scotch_yoke_moves_harmonically():
    model, _, table = run("scotch_yoke", t_end=1.0, output_step=0.01)
    p = model.parameters
    phase = p["omega"] * table["t"]
    # kinematics: measured errors 3e-17 m and 2e-14 m/s^2
    np.testing.assert_allclose(table["yoke.x"], p["x0"] + p["r"] * np.cos(phase),
                               rtol=0, atol=1e-10)
    np.testing.assert_allclose(table["yoke.ax"], -p["r"] * p["omega"]**2 * np.cos(phase),
                               rtol=0, atol=1e-8)


def test_spatial_rsur_rocker_follows_loop_closure():
    model, _, table = run("spatial_rsur", t_end=1.0, output_step=0.01)
    p = model.parameters
    pivot = (0.0, p["Dy"], p["Dz"])
    phi = np.arctan2(table["rocker.z"] - p["Dz"], table["rocker.y"] - p["Dy"])
    expected = cf.rsur_rocker_angle(p["omega"] * table["t"], p["a"], p["c"], p["Lc"], pivot,
                                    p["phi0"])
    # Newton to machine precision on both sides: 1e-9 rad
    np.testing.assert_allclose(phi, expected, rtol=0, atol=1e-9)
    assert np.ptp(phi) > 0.5  # a crank-rocker: the rocker swings ~0.8 rad


def test_robot_arm_forward_kinematics_and_static_torques():
    model, _, table = run("robot_arm_3r", t_end=1.0, output_step=0.01)
    p = model.parameters
    t = table["t"]
    q1, q2, q3 = (p[a] * (t - np.sin(p["wf"] * t) / p["wf"]) for a in ("A1", "A2", "A3"))
    upper, fore = cf.arm_forward_kinematics(q1, q2, q3, p["h0"], p["L1"], p["L2"])
    for body, exact in (("upper_arm", upper), ("forearm", fore)):
        position = np.column_stack([table[f"{body}.{c}"] for c in "xyz"])
        # kinematics: Newton converges to ~1e-13 m
        np.testing.assert_allclose(position, exact, rtol=0, atol=1e-10)
    # t = 0: at rest, zero acceleration, links horizontal along x: the joint holds the gravity
    # moment of everything beyond it, about +y: -g (m1 L1/2 + m2 (L1 + L2/2)) and -g m2 L2/2
    g = 9.81
    shoulder = -g * (p["m1"] * p["L1"] / 2 + p["m2"] * (p["L1"] + p["L2"] / 2))
    elbow = -g * p["m2"] * p["L2"] / 2
    # direct linear solve at t = 0: roundoff only
    np.testing.assert_allclose([table["shoulder.ty"][0], table["elbow.ty"][0]],
                               [shoulder, elbow], rtol=1e-12, atol=1e-10)


# -------------------------------------------------------------------------------- Bricard
def test_bricard_has_one_dof_with_a_redundant_row_and_keeps_its_loop_closed():
    model, functions, table = run("bricard", t_end=0.3, output_step=0.01)
    report, _ = casmech.check(functions)
    assert report.dof == 1  # Gruebler says 0
    assert len(report.redundant) == 1
    bodies = {b.name: b for b in model.bodies}
    states = {name: cf.body_state(table, name) for name in bodies}

    def point_and_axis(body, joint):
        """The joint point and axis as carried by `body` (ground: fixed)."""
        at, axis = joint.vectors["at"], joint.vectors["axis"]
        if body == "ground":
            return np.broadcast_to(at, (len(table["t"]), 3)), np.broadcast_to(axis, (
                len(table["t"]), 3))
        b, s = bodies[body], states[body]
        a0 = cf.rotation(b.euler_parameters)[0]
        local_at, local_axis = a0.T @ (at - b.position), a0.T @ axis
        return s["r"] + s["A"] @ local_at, s["A"] @ local_axis

    for joint in model.joints:
        point_i, axis_i = point_and_axis(joint.body_i, joint)
        point_j, axis_j = point_and_axis(joint.body_j, joint)
        # closure computed here from positions and Euler parameters: |Phi| <= 1e-9 by the
        # projection, so joint points agree to 1e-8 m and the hinge axes stay parallel
        np.testing.assert_allclose(point_i, point_j, rtol=0, atol=1e-8)
        np.testing.assert_allclose(np.cross(axis_i, axis_j), 0.0, rtol=0, atol=1e-8)
    assert np.ptp(table["rod3.y"]) > 0.02  # it does move: rod3 falls 0.04 m in 0.3 s
    energy = cf.mechanical_energy(model, table)
    # measured drift 7e-8 J over 0.5 s on |E| = 29.4 J (rtol 1e-8)
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-6)


# -------------------------------------------------------------------------------- couplings
def test_gear_pair_swings_at_the_closed_form_frequency():
    """The pendulum on the pinion swings with the wheel's inertia reduced through the gear:
    omega^2 = m g l / (J1 + m l^2 + (r1 / r2)^2 J2) about the hanging equilibrium."""
    model = casmech.load(MODELS / "gear_pair.yaml")
    p = model.parameters
    j1 = p["m1"] * p["r1"] ** 2 / 2
    j2 = p["m2"] * p["r2"] ** 2 / 2
    omega = np.sqrt(p["m"] * 9.81 * p["l"]
                    / (j1 + p["m"] * p["l"] ** 2 + (p["r1"] / p["r2"]) ** 2 * j2))
    functions = casmech.compile(model)
    linear = casmech.analyze(functions, "modal").linear_model
    # eigenvalues of the reduced linear model at the equilibrium: round-off
    np.testing.assert_allclose(linear.frequency_hz, [omega / (2 * np.pi)], rtol=1e-9, atol=0)


def test_lead_screw_nut_falls_at_the_closed_form_acceleration():
    """a = g m / (m + J (2 pi / lead)^2) all the way down (about 40 turns)."""
    model, _, table = run("lead_screw")
    p = model.parameters
    inertia = p["m"] * (p["r_in"] ** 2 + p["r_out"] ** 2) / 2
    a = 9.81 * p["m"] / (p["m"] + inertia * (2 * np.pi / p["lead"]) ** 2)
    # the consistent initial acceleration solves a linear system: round-off
    np.testing.assert_allclose(table["nut.az"][0], -a, rtol=1e-9, atol=0)
    t = table["t"]
    np.testing.assert_allclose(table["thread.displacement"], -a * t ** 2 / 2, rtol=1e-6,
                               atol=1e-9)  # positions to the integrator's tolerance
