"""Exact Coulomb stick and slip at contact points (`friction: {model: exact}`:
elements/forces/contact.py, runtime/contact_friction.py), against closed forms written here:
a block held on an incline inside its friction cone, one sliding down it, and one pushed by a
force ramp on a flat floor.

The blocks rest on the compliant normal law at its static penetration d0 = m g cos(theta) / k
(k the summed stiffness of the points), so the normal force starts settled; the incline is the
floor with gravity tilted by theta about y (down the slope is +x)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import casmech
from casmech.api import results_table

M, G, K = 2.0, 9.81, 1.0e5  # block mass, gravity, stiffness of one contact point

BOX = """casmech: 1
name: block_on_incline
parameters: {{theta: {theta}, m: 2.0, g: 9.81, d0: {d0}, k: {k}}}
gravity: [g * sin(theta), 0, -g * cos(theta)]
bodies:
  - {{name: block, mass: m, inertia: [0.01, 0.012, 0.014], position: [0, 0, 0.05 - d0]}}
forces:
  - name: pad
    type: points_plane
    body_j: block
    points: [[-0.1, -0.08, -d0], [0.1, -0.08, -d0], [-0.1, 0.08, -d0], [0.1, 0.08, -d0]]
    normal: {{law: linear, stiffness: k, damping: 400}}
    friction: {{static: {mu_s}, dynamic: {mu_d}{model}}}
{extra}analysis: {{type: dynamics, t_end: {t_end}, output_step: 0.01, rtol: 1.0e-10,
           atol: 1.0e-12{formulation}}}
"""

FOOT = """  - name: foot{n}
    type: sphere_plane
    body_j: block
    radius: 0.01
    center: [{x}, {y}, 0.01 - d0]
    normal: {{law: linear, stiffness: k, damping: 400}}
    friction: {{static: {mu_s}, dynamic: {mu_d}, model: exact}}
"""


def box(theta, mu_s, mu_d, model="exact", t_end=2.0, extra="", formulation=""):
    d0 = M * G * math.cos(theta) / (4 * K)
    return BOX.format(theta=theta, mu_s=mu_s, mu_d=mu_d, d0=d0, k=K, t_end=t_end,
                      model=f", model: {model}" if model else "", extra=extra,
                      formulation=f", formulation: {formulation}" if formulation else "")


def tripod(theta, mu_s, mu_d):
    """The block on three sphere_plane feet (three elements) instead of its pad."""
    d0 = M * G * math.cos(theta) / (3 * K)
    feet = "".join(FOOT.format(n=n, x=x, y=y, mu_s=mu_s, mu_d=mu_d)
                   for n, (x, y) in enumerate([(-0.1, -0.08), (0.1, 0.0), (-0.1, 0.08)]))
    text = box(theta, mu_s, mu_d).replace(f"d0: {M * G * math.cos(theta) / (4 * K)}",
                                         f"d0: {d0}")
    start, end = text.index("  - name: pad"), text.index("analysis:")
    return text[:start] + feet + text[end:]


def run(text: str):
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions)
    names, values = results_table(functions, result)
    return result, dict(zip(names, values.T, strict=True))


def material_point(columns, s_bar) -> np.ndarray:
    """The global path of the block's material point s_bar (body frame)."""
    quat = np.c_[columns["block.e1"], columns["block.e2"], columns["block.e3"],
                 columns["block.e0"]]
    r = np.c_[columns["block.x"], columns["block.y"], columns["block.z"]]
    return r + Rotation.from_quat(quat).apply(s_bar)


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))


@pytest.mark.parametrize("formulation", ["", "joint", "romega"])
def test_box_on_incline_inside_the_cone_sticks(formulation):
    theta, mu = 0.3, 0.5
    assert math.tan(theta) < mu
    d0 = M * G * math.cos(theta) / (4 * K)
    result, columns = run(box(theta, mu, 0.4, formulation=formulation))
    assert result.metadata["formulation"] == (formulation or "rp")
    # the contact points are held where they stuck (the mid-overlap point of a corner: the
    # block may pitch a little on the compliant normal, its points on the floor do not slide)
    corner = material_point(columns, [-0.1, -0.08, -0.05 + d0 / 2])
    assert np.max(np.abs(corner[:, :2] - corner[0, :2])) < 1e-9
    assert result.metadata["friction_start_modes"] == dict.fromkeys(
        [f"pad[{k}]" for k in range(4)], "stuck")
    assert result.metadata["friction_switches"] == []
    # the holding force is the slope's pull m g sin(theta), once the pitch transient has
    # died out (damped within 0.5 s): 1e-6 relative, the integrator's tolerance on a settled
    # multiplier
    settled = np.asarray(result.times) > 1.0
    np.testing.assert_allclose(columns["pad.friction_force"][settled], M * G * math.sin(theta),
                               rtol=1e-6, atol=0)


def test_the_smooth_law_of_the_same_box_creeps():
    theta, mu = 0.3, 0.5
    d0 = M * G * math.cos(theta) / (4 * K)
    # the smooth law creeps down the slope, far more than the exact law's 1e-9 m (its slip
    # below the stiction velocity is what holds it)
    _, smooth = run(box(theta, mu, 0.4, model=""))
    creep = material_point(smooth, [-0.1, -0.08, -0.05 + d0 / 2])
    assert creep[-1, 0] - creep[0, 0] > 1e-4


def test_three_sphere_feet_on_incline_inside_the_cone_stick():
    theta, mu = 0.3, 0.5
    d0 = M * G * math.cos(theta) / (3 * K)
    result, columns = run(tripod(theta, mu, 0.4))
    # the rows hold the feet's centroid (its material point does not move at all) and the
    # turn about the normal; a foot away from the centroid moves by the second order of the
    # block's pitch on the compliant normal (its rho (1 - cos(pitch)), a few nm while the
    # start's pitch transient dies out), then not at all: no creep
    centroid = material_point(columns, [-0.1 / 3, 0.0, -0.05 + d0 / 2])
    assert np.max(np.abs(centroid[:, :2] - centroid[0, :2])) < 1e-9
    settled = np.asarray(result.times) > 0.5
    for x, y in [(-0.1, -0.08), (0.1, 0.0), (-0.1, 0.08)]:
        foot = material_point(columns, [x, y, -0.05 + d0 / 2])[settled]
        assert np.max(np.abs(foot[:, :2] - foot[0, :2])) < 1e-9
        assert np.max(np.abs(foot[:, :2] - [x, y])) < 2e-8
    assert set(result.metadata["friction_start_modes"].values()) == {"stuck"}
    # three elements' points on one plane share one holding force: m g sin(theta) in all
    settled = np.asarray(result.times) > 1.0
    total = sum(columns[f"foot{n}.friction_force"][settled] for n in range(3))
    assert np.all(total >= M * G * math.sin(theta) * (1 - 1e-6))


@pytest.mark.parametrize("formulation", ["", "rp", "joint"])
def test_box_on_incline_outside_the_cone_slides_at_g_sin_minus_mu_cos(formulation):
    theta, mu_s, mu_d = 0.3, 0.25, 0.2
    assert math.tan(theta) > mu_s
    result, columns = run(box(theta, mu_s, mu_d, formulation=formulation))
    a = G * (math.sin(theta) - mu_d * math.cos(theta))
    settled = np.asarray(result.times) > 1.0
    # closed form once the normal law has settled: Coulomb's sliding friction mu_d N with
    # N = m g cos(theta); 1e-8 relative is well above the run's rtol 1e-10
    np.testing.assert_allclose(columns["block.ax"][settled], a, rtol=1e-8, atol=0)
    np.testing.assert_allclose(columns["pad.friction_force"][settled],
                               mu_d * M * G * math.cos(theta), rtol=1e-8, atol=0)
    # it starts stuck, slips at once (a point released at t > 0 past mu_s N), never sticks
    modes = [s["mode"] for s in result.metadata["friction_switches"]]
    assert "stuck" not in modes
    assert result.metadata["friction_switches"][0]["t"] < 1e-3
    # straight down the slope: no sideways slip or yaw
    assert np.max(np.abs(columns["block.y"])) < 1e-12
    # the energy the friction takes once settled: its work mu_d m g cos(theta) per metre
    # (the normal law's damping does none on a steady slide); 1e-7 relative to that work
    e, x = columns["energy"][settled], columns["block.x"][settled]
    np.testing.assert_allclose(e[0] - e, mu_d * M * G * math.cos(theta) * (x - x[0]),
                               rtol=1e-7, atol=1e-9)


def test_box_pushed_by_a_force_ramp_sticks_until_mu_s_n_then_slides():
    mu_s, mu_d, rate = 0.5, 0.3, 20.0  # the push grows by `rate` N/s
    d0 = M * G / (4 * K)
    # pushed along x at the height of the held points (mid-overlap), so the push does not
    # tip the block and each corner carries N = m g / 4
    push = (f"  - {{name: push, type: force, body: block, at: [0, 0, {-d0 / 2!r}], "
            f"value: [{rate} * t, 0, 0]}}\n")
    result, columns = run(box(0.0, mu_s, mu_d, t_end=1.0, extra=push))
    t_slip = mu_s * M * G / rate  # the push reaches the static limit
    switches = result.metadata["friction_switches"]
    assert {s["mode"] for s in switches} == {"sliding"}
    # every corner slips when the push reaches mu_s m g: the located event, to the rtol
    np.testing.assert_allclose([s["t"] for s in switches], t_slip, rtol=1e-7, atol=0)
    t = np.asarray(result.times)
    before = t < t_slip
    assert np.max(np.abs(material_point(columns, [0.1, 0.08, -0.05 + d0 / 2])[before, 0]
                         - 0.1)) < 1e-9
    # then m v' = rate t - mu_d m g: v(t) = (rate (t^2 - t_s^2) / 2 - mu_d m g (t - t_s)) / m
    after = t > t_slip + 0.05
    v = (rate * (t[after] ** 2 - t_slip ** 2) / 2 - mu_d * M * G * (t[after] - t_slip)) / M
    np.testing.assert_allclose(columns["block.vx"][after], v, rtol=1e-7, atol=1e-12)


def test_box_twisted_by_a_torque_ramp_slips_at_mu_s_m_g_rho_then_spins():
    mu_s, mu_d, rate = 0.5, 0.3, 4.0  # the torque about the normal grows by `rate` N m/s
    rho = math.hypot(0.1, 0.08)  # each corner's distance from the centre
    twist = f"  - {{name: twist, type: torque, body: block, value: [0, 0, {rate} * t]}}\n"
    result, columns = run(box(0.0, mu_s, mu_d, t_end=1.0, extra=twist))
    # four corners at rho, each carrying m g / 4: held while T <= mu_s m g rho (Coulomb's
    # limit of the body, which the load-shared holding torque reaches at every corner at once)
    t_slip = mu_s * M * G * rho / rate
    switches = result.metadata["friction_switches"]
    assert [s["mode"] for s in switches] == ["sliding"] * 4
    # the located event, to the rtol
    np.testing.assert_allclose([s["t"] for s in switches], t_slip, rtol=1e-7, atol=0)
    t = np.asarray(result.times)
    assert np.max(np.abs(columns["block.wz"][t < t_slip])) < 1e-9
    # then J w' = rate t - mu_d m g rho (each corner slides along its circle)
    after = t > t_slip + 0.05
    w = (rate * (t[after] ** 2 - t_slip ** 2) / 2 - mu_d * M * G * rho * (t[after] - t_slip)) \
        / 0.014
    # to 1e-6: the block's small pitch and roll on the compliant normal while it spins
    np.testing.assert_allclose(columns["block.wz"][after], w, rtol=1e-6, atol=1e-12)


def test_box_launched_on_the_floor_slides_to_rest_and_sticks():
    mu_s, mu_d, v0 = 0.5, 0.3, 1.2
    text = box(0.0, mu_s, mu_d, t_end=1.0).replace("position: [0, 0, 0.05 - d0]}",
                                                   f"position: [0, 0, 0.05 - d0], "
                                                   f"velocity: [{v0}, 0, 0]}}")
    result, columns = run(text)
    t_stop = v0 / (mu_d * G)  # closed form: the friction's impulse mu_d m g t equals m v0
    switches = result.metadata["friction_switches"]
    assert set(result.metadata["friction_start_modes"].values()) == {"sliding"}
    assert {s["mode"] for s in switches} == {"stuck"}
    # the located stops (slip speed along its direction reaching 0), to the rtol
    np.testing.assert_allclose([s["t"] for s in switches], t_stop, rtol=1e-7, atol=0)
    t = np.asarray(result.times)
    d0 = M * G / (4 * K)
    x = material_point(columns, [0.0, 0.0, -0.05 + d0 / 2])[:, 0]  # the held centroid
    # it stops after v0^2 / (2 mu_d g), then stays (no creep with no load along the floor).
    # 5e-5: the launch shakes the block on its compliant normal (pitch and bounce, damped in
    # some 0.05 s), so sum N and the deceleration vary about m g and mu_d g early on; their
    # impulse is exact (the stop time above, to 1e-7), the distance they give not quite
    np.testing.assert_allclose(x[t > t_stop], v0 ** 2 / (2 * mu_d * G), rtol=5e-5, atol=0)
    assert np.ptp(x[t > t_stop]) < 1e-9
    # the friction never adds energy (a rise at most the integration error at rtol 1e-10)
    energy = columns["energy"]
    assert np.max(np.diff(energy)) < 1e-9 * np.max(np.abs(energy))


def test_box_dropped_on_incline_inside_the_cone_lands_slides_and_sticks():
    theta = 0.3
    # released 10 mm above the floor (apart: every point free), it lands with the slope's
    # share of its fall as slip, which the impact's friction stops
    text = box(theta, 0.5, 0.4, t_end=1.0).replace(
        "position: [0, 0, 0.05 - d0]}", "position: [0, 0, 0.06]}").replace("-d0]", "0.01]")
    result, columns = run(text)
    assert set(result.metadata["friction_start_modes"].values()) == {"free"}
    switches = result.metadata["friction_switches"]
    # the four corners touch at once: where the free fall along the normal covers 10 mm
    touch = [s["t"] for s in switches[:4]]
    np.testing.assert_allclose(touch, math.sqrt(2 * 0.01 / (G * math.cos(theta))), rtol=1e-7,
                               atol=0)  # the located touch, to the rtol
    assert {s["mode"] for s in switches[:4]} == {"sliding"}
    final = {s["contact"]: s["mode"] for s in switches}
    assert final == dict.fromkeys([f"pad[{k}]" for k in range(4)], "stuck")
    t = np.asarray(result.times)
    # no creep once the landing's rocking has died out (while it rocks, the bottom's centre
    # moves by the pitch times its height below the held mid-overlap point: 1e-7 m)
    assert switches[-1]["t"] < 0.1
    held = material_point(columns, [0.0, 0.0, -0.05])[t > 0.5]
    assert np.max(np.abs(held[:, :2] - held[0, :2])) < 1e-9
    assert np.max(np.abs(columns["block.y"])) < 1e-12


def test_box_pushed_high_tips_over_its_front_edge_which_stays_stuck():
    rate, height = 20.0, 0.3  # a push growing by `rate` N/s, at `height` above the floor
    d0 = M * G / (4 * K)
    push = (f"  - {{name: push, type: force, body: block, at: [0, 0, {height}], "
            f"value: [{rate} * t, 0, 0]}}\n")
    result, columns = run(box(0.0, 0.9, 0.8, t_end=0.5, extra=push))
    # the back corners (x = -0.1) lift when the push's moment about the front edge reaches
    # the weight's, F (height + d0 / 2) = m g 0.1: rigid statics, 1e-3 for the compliant
    # normal (the front edge sinks as it takes the load)
    t_tip = M * G * 0.1 / (height + d0 / 2) / rate
    switches = result.metadata["friction_switches"]
    assert sorted((s["contact"], s["mode"]) for s in switches) == [("pad[0]", "free"),
                                                                   ("pad[2]", "free")]
    np.testing.assert_allclose([s["t"] for s in switches], t_tip, rtol=1e-3, atol=0)
    # it tips over the front edge, which stays where it stuck (mu_s = 0.9: no slip)
    t = np.asarray(result.times)
    assert columns["block.wy"][-1] > 1.0
    # (the point held is the mid-overlap point where the edge was re-held as the back
    # lifted, deeper than d0 / 2 by the load the edge took: this one moves by the pitch
    # times that depth difference, under d0 (25 um) times the 0.15 rad the block turns)
    edge = material_point(columns, [0.1, 0.0, -0.05 + d0 / 2])
    pitch = 2 * np.arcsin(np.abs(columns["block.e2"]))
    assert np.all(np.abs(edge[:, 0] - 0.1) <= d0 * pitch + 1e-12)
    assert pitch[t < t_tip * (1 - 1e-3)].max() < 1e-3  # upright until it tips
