"""Joint friction with load parts on several joints (equations/friction_load.py: their loads
solved together): two blocks on two inclines, a block sliding on a wedge that slides on the
floor (each friction's load depends on the other's force), and two blocks held until force
ramps reach their static limits, against closed forms written here."""

from __future__ import annotations

import math

import numpy as np
import pytest

import casmech
from casmech.api import results_table
from casmech.errors import AnalysisError

G = 9.81


def run(text: str):
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions)
    names, values = results_table(functions, result)
    return result, dict(zip(names, values.T, strict=True))


def block(name: str, theta: float, y: float, friction: str, extra: str = "") -> tuple[str, str]:
    """A 2 kg block on its own incline of angle theta (the axis down the slope) at y."""
    body = f"  - {{name: {name}, mass: 2.0, inertia: [0.1, 0.1, 0.1], position: [0, {y}, 0]}}\n"
    joint = (f"  - {{name: {name}_slide, type: translational, body_i: ground, body_j: {name}, "
             f"at: [0, {y}, 0], axis: [{math.cos(theta)}, 0, {-math.sin(theta)}], "
             f"friction: {friction}{extra}}}\n")
    return body, joint


def model(parts, formulation="joint", forces="", t_end=2.0) -> str:
    bodies = "".join(b for b, _ in parts)
    joints = "".join(j for _, j in parts)
    return f"""casmech: 1
name: coupled_friction
gravity: [0, 0, -{G}]
bodies:
{bodies}joints:
{joints}{forces}analysis: {{type: dynamics, t_end: {t_end}, output_step: 0.01, rtol: 1.0e-10,
           atol: 1.0e-12, formulation: {formulation}}}
"""


@pytest.mark.parametrize("formulation", ["joint", "rp"])
def test_two_blocks_on_two_inclines_each_slide_at_g_sin_minus_mu_cos(formulation):
    """Two independent mechanisms in one model, both load parts sliding at once."""
    cases = {"a": (0.6, 0.5), "b": (0.9, 0.3)}
    parts = [block(n, theta, y, f"{{mu: {mu}}}") for (n, (theta, mu)), y
             in zip(cases.items(), (0.0, 2.0), strict=True)]
    result, columns = run(model(parts, formulation))
    t = np.array(result.times)
    for name, (theta, mu) in cases.items():
        a = G * (math.sin(theta) - mu * math.cos(theta))
        # closed form s = a t^2 / 2 from rest, 1e-9 relative; atol: IDAS's (rp) absolute
        # error at atol 1e-12 over the first steps
        np.testing.assert_allclose(columns[f"{name}_slide.displacement"], 0.5 * a * t ** 2,
                                   rtol=1e-9, atol=1e-11)
        # the load part is mu m g cos(theta), against the motion; the law on the solved loads
        np.testing.assert_allclose(columns[f"{name}_slide.friction"],
                                   -mu * 2.0 * G * math.cos(theta), rtol=1e-10, atol=0)
        assert np.all(columns[f"{name}_slide.friction_mode"] == 1)


M_WEDGE, M_BLOCK, THETA, MU_FLOOR, MU_SLOPE = 3.0, 1.0, 0.5, 0.1, 0.2
V_WEDGE, V_BLOCK = -0.5, 0.5  # initial rates: the wedge backing off, the block down the slope


def wedge(formulation: str) -> str:
    """A wedge on the floor (rail along x) and a block on its slope (axis down the slope)."""
    c, s = math.cos(THETA), math.sin(THETA)
    return f"""casmech: 1
name: wedge
gravity: [0, 0, -{G}]
bodies:
  - {{name: wedge, mass: {M_WEDGE}, inertia: [0.2, 0.3, 0.2], position: [0, 0, 0]}}
  - {{name: block, mass: {M_BLOCK}, inertia: [0.01, 0.01, 0.01], position: [0, 0, 0.5]}}
joints:
  - {{name: floor, type: translational, body_i: ground, body_j: wedge, at: [0, 0, 0],
     axis: [1, 0, 0], friction: {{mu: {MU_FLOOR}}}, initial: {{displacement_dot: {V_WEDGE}}}}}
  - {{name: slope, type: translational, body_i: wedge, body_j: block, at: [0, 0, 0.5],
     axis: [{c}, 0, {-s}], friction: {{mu: {MU_SLOPE}}},
     initial: {{displacement_dot: {V_BLOCK}}}}}
analysis: {{type: dynamics, t_end: 0.5, output_step: 0.01, rtol: 1.0e-10, atol: 1.0e-12,
           formulation: {formulation}}}
"""


def wedge_closed_form():
    """(A, b, N, R): the wedge's acceleration along x, the block's along the slope (relative),
    the slope's and the floor's normal forces, from Newton's laws of the two bodies with the
    block sliding down (friction mu2 N up the slope) and the wedge moving to -x (friction
    mu1 R to +x): four linear equations."""
    c, s, m, big = math.cos(THETA), math.sin(THETA), M_BLOCK, M_WEDGE
    # unknowns A, b, N, R
    lhs = np.array([
        [m * s, 0, -1, 0],                    # block normal to the slope: N - m g c = m A s
        [m * c, m, MU_SLOPE, 0],              # block along the slope
        [big, 0, s - MU_SLOPE * c, -MU_FLOOR],  # wedge along x
        [0, 0, c + MU_SLOPE * s, -1]])        # wedge vertical: R = M g + N (c + mu2 s)
    rhs = np.array([-m * G * c, m * G * s, 0, -big * G])
    return np.linalg.solve(lhs, rhs)


@pytest.mark.parametrize("formulation", ["joint", "rp", "romega"])
def test_a_block_on_a_sliding_wedge_moves_as_newtons_laws_say(formulation):
    """Each friction's load depends on the other's force (the slope's friction changes the
    floor's load, the floor's friction the wedge's acceleration and so the slope's load):
    the loads solved together give the constant accelerations of the closed form."""
    acc_wedge, acc_block, normal, floor = wedge_closed_form()
    # the assumed directions hold over the run (the wedge slows but still backs off)
    assert V_WEDGE + 0.5 * acc_wedge < 0 < V_BLOCK + 0.5 * acc_block
    assert normal > 0 and floor > 0
    result, columns = run(wedge(formulation))
    t = np.array(result.times)
    # closed form from the initial rates, integrated at rtol 1e-10 (atol: IDAS's absolute)
    np.testing.assert_allclose(columns["floor.displacement"], V_WEDGE * t + acc_wedge * t ** 2
                               / 2, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(columns["slope.displacement"], V_BLOCK * t + acc_block * t ** 2
                               / 2, rtol=1e-9, atol=1e-10)
    # the friction forces are mu times the closed form's normal forces (rp: the DAE's
    # multipliers to IDAS's tolerance; the others: one solve, roundoff)
    np.testing.assert_allclose(columns["floor.friction"], MU_FLOOR * floor, rtol=1e-7, atol=0)
    np.testing.assert_allclose(columns["slope.friction"], -MU_SLOPE * normal, rtol=1e-7,
                               atol=0)
    assert result.metadata["friction_switches"] == []
    # the energy lost is the work of the frictions (exact trapezoid: constant forces,
    # rates linear in t), to the integration error
    work = sum(np.trapezoid(columns[f"{j}.friction"] * columns[f"{j}.displacement_dot"], t)
               for j in ("floor", "slope"))
    lost = columns["energy"][-1] - columns["energy"][0]
    assert work < 0
    np.testing.assert_allclose(lost, work, rtol=1e-7, atol=0)  # integration error at 1e-10


def test_two_blocks_held_by_static_load_parts_slip_where_their_ramps_reach_the_limits():
    """Force ramps k t up two inclines' slopes (against their weights' pull down it) ... held
    until k t = m g (sin + mu_s cos) (up the slope), then sliding with mu."""
    theta, m = 0.3, 2.0
    spec = {"a": (0.35, 0.2, 20.0), "b": (0.5, 0.4, 30.0)}  # mu_s, mu, k
    assert all(math.tan(theta) < mu_s for mu_s, _, _ in spec.values())  # held at rest
    parts, forces = [], "forces:\n"
    for (name, (mu_s, mu, k)), y in zip(spec.items(), (0.0, 2.0), strict=True):
        parts.append(block(name, theta, y, f"{{mu: {mu}, mu_static: {mu_s}}}"))
        forces += (f"  - {{name: {name}_push, type: force, body: {name}, value: "
                   f"[{-k * math.cos(theta)} * t, 0, {k * math.sin(theta)} * t]}}\n")
    result, columns = run(model(parts, "joint", forces, t_end=1.0))
    t = np.array(result.times)
    switches = result.metadata["friction_switches"]
    assert sorted(s["joint"] for s in switches) == ["a_slide", "b_slide"]
    for name, (mu_s, mu, k) in spec.items():
        start = m * G * (math.sin(theta) + mu_s * math.cos(theta)) / k
        (switch,) = [s for s in switches if s["joint"] == f"{name}_slide"]
        assert switch["mode"] == -1  # up the slope
        # the located event, to the run's tolerance
        np.testing.assert_allclose(switch["t"], start, rtol=1e-9, atol=0)
        # then m s'' = m g (sin + mu cos) - k t (the axis down the slope, the friction too)
        after = t > start
        tau = t[after] - start
        slide = -(k * (t[after] ** 3 - start ** 3) / 6 - k * start ** 2 * tau / 2) / m \
            + G * (math.sin(theta) + mu * math.cos(theta)) * tau ** 2 / 2
        np.testing.assert_allclose(columns[f"{name}_slide.displacement"][after], slide,
                                   rtol=1e-7, atol=1e-10)  # integrated at rtol 1e-10
        stuck = t < start
        assert np.max(np.abs(columns[f"{name}_slide.displacement"][stuck])) < 1e-9


def test_frictions_that_would_lock_two_joints_together_are_an_analysis_error():
    """The wedge with mu far past the slope's self-locking: the loads' matrix has spectral
    radius >= 1, an error naming both joints."""
    text = wedge("joint").replace(f"mu: {MU_FLOOR}", "mu: 3.0").replace(f"mu: {MU_SLOPE}",
                                                                         "mu: 3.0")
    functions = casmech.compile(casmech.loads(text))
    with pytest.raises(AnalysisError) as raised:
        casmech.analyze(functions)
    message = str(raised.value)
    assert "Painleve" in message and "'floor'" in message and "'slope'" in message


def test_a_held_wedge_slips_where_a_ramp_reaches_its_load_dependent_limit():
    """The wedge held by the floor (mu_static) while the block slides down its slope: the
    floor's load and the force needed to hold the wedge come from the block's sliding friction
    (itself a load part); a ramp k t to -x on the wedge makes it slip at
    k t* = mu_s R - N (sin - mu2 cos), after which both slide, their loads solved together."""
    k, mu_s, t_end = 20.0, 0.2, 0.6
    c, s, m, big = math.cos(THETA), math.sin(THETA), M_BLOCK, M_WEDGE
    text = wedge("joint").replace(f"friction: {{mu: {MU_FLOOR}}}, initial: {{displacement_dot: "
                                  f"{V_WEDGE}}}", f"friction: {{mu: {MU_FLOOR}, mu_static: "
                                  f"{mu_s}}}")
    text = text.replace("analysis:", f"forces:\n  - {{name: push, type: force, body: wedge, "
                        f"value: [-{k} * t, 0, 0]}}\nanalysis:").replace("t_end: 0.5",
                                                                         f"t_end: {t_end}")
    assert "mu_static" in text and "push" in text
    # held: the block on a fixed slope
    normal = m * G * c
    floor = big * G + normal * (c + MU_SLOPE * s)
    start = (mu_s * floor - normal * (s - MU_SLOPE * c)) / k
    assert 0 < start < t_end
    # both sliding: the wedge's equation of wedge_closed_form with the ramp, A = A0 + A1 t
    lhs = np.array([[m * s, 0, -1, 0], [m * c, m, MU_SLOPE, 0],
                    [big, 0, s - MU_SLOPE * c, -MU_FLOOR], [0, 0, c + MU_SLOPE * s, -1]])
    base = np.linalg.solve(lhs, [-m * G * c, m * G * s, 0, -big * G])
    slope = np.linalg.solve(lhs, [0, 0, -k, 0])  # per unit t
    result, columns = run(text)
    switches = result.metadata["friction_switches"]
    assert [(w["joint"], w["mode"]) for w in switches] == [("floor", -1)]
    # the located event, to the run's tolerance
    np.testing.assert_allclose(switches[0]["t"], start, rtol=1e-9, atol=0)
    t = np.array(result.times)
    held, after = t < start, t > start
    assert np.max(np.abs(columns["floor.displacement"][held])) < 1e-9
    tau = t[after] - start

    def twice(a0, a1):  # the double integral from rest at `start` of a0 + a1 t
        return a0 * tau ** 2 / 2 + a1 * ((t[after] ** 3 - start ** 3) / 6 - start ** 2 * tau / 2)

    acc_free = G * (s - MU_SLOPE * c)  # the block on the held wedge
    block_start = V_BLOCK * start + acc_free * start ** 2 / 2
    # the assumed directions hold over the run: the closed forms' rates on the grid
    wedge_rate = base[0] * tau + slope[0] * (t[after] ** 2 - start ** 2) / 2
    block_rate = V_BLOCK + acc_free * start + base[1] * tau + slope[1] * (
        t[after] ** 2 - start ** 2) / 2
    assert np.all(wedge_rate[1:] < 0) and np.all(block_rate > 0)
    # closed forms integrated at rtol 1e-10
    np.testing.assert_allclose(columns["floor.displacement"][after], twice(base[0], slope[0]),
                               rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(columns["slope.displacement"][after], block_start + (
        V_BLOCK + acc_free * start) * tau + twice(base[1], slope[1]), rtol=1e-8, atol=1e-10)


@pytest.mark.parametrize("formulation", ["joint", "rp"])
def test_an_unloaded_wedge_and_block_glide_at_their_initial_rates(formulation):
    """Without gravity the block glides down the slope of the gliding wedge with no load on
    either joint: the coupled load parts are 0 (their derivative at a zero load is no 0/0
    in Newton's steps) and both move at their initial rates."""
    text = wedge(formulation).replace(f"gravity: [0, 0, -{G}]", "gravity: [0, 0, 0]")
    result, columns = run(text)
    t = np.array(result.times)
    for name, rate in (("floor", V_WEDGE), ("slope", V_BLOCK)):
        # uniform motion, integrated at rtol 1e-10 (atol: IDAS's absolute error)
        np.testing.assert_allclose(columns[f"{name}.displacement"], rate * t, rtol=1e-9,
                                   atol=1e-11)
        # no load, no Coulomb part: no friction, to roundoff
        np.testing.assert_allclose(columns[f"{name}.friction"], 0, rtol=0, atol=1e-12)
