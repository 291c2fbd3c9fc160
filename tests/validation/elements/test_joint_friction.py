"""Joint friction with exact sticking (equations/friction.py, runtime/friction.py), against
closed forms written here: the spring-inertia oscillator with Coulomb friction and a block on
an incline."""

from __future__ import annotations

import math

import numpy as np
import pytest

import casmech
from casmech.api import results_table
from casmech.errors import ModelError
from tests.conftest import MODELS

OSCILLATOR = """casmech: 1
name: friction_oscillator
parameters: {{k: 10.0, J: 0.5, Tc: 1.5}}
gravity: [0, 0, 0]
bodies:
  - {{name: disk, mass: 1.0, inertia: [J, J, J], position: [0, 0, 0]}}
joints:
  - name: pivot
    type: revolute
    body_i: ground
    body_j: disk
    at: [0, 0, 0]
    axis: [0, 0, 1]
    initial: {{angle: 1.0, angle_dot: 0}}
    friction: {{coulomb: Tc}}
forces:
  - {{name: spring, type: rsda, joint: pivot, stiffness: k}}
analysis: {{type: dynamics, t_end: 3.0, output_step: 0.01, rtol: 1.0e-10, atol: 1.0e-12,
           formulation: {formulation}}}
"""

INCLINE = """casmech: 1
name: incline
parameters: {{theta: {theta}, mu: {mu}, m: 2.0, g: 9.81}}
gravity: [0, 0, -g]
bodies:
  - {{name: block, mass: m, inertia: [0.1, 0.1, 0.1], position: [0, 0, 0]}}
joints:
  - name: slide
    type: translational
    body_i: ground
    body_j: block
    at: [0, 0, 0]
    axis: [cos(theta), 0, -sin(theta)]
    friction: {{coulomb: mu * m * g * cos(theta)}}
analysis: {{type: dynamics, t_end: 2.0, output_step: 0.01, rtol: 1.0e-10, atol: 1.0e-12}}
"""


def run(text: str):
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions)
    names, values = results_table(functions, result)
    return result, dict(zip(names, values.T, strict=True))


@pytest.mark.parametrize("formulation", ["joint", "rp"])
def test_coulomb_oscillator_loses_2tc_over_k_per_half_cycle_and_sticks(formulation):
    k, inertia, tc, a0 = 10.0, 0.5, 1.5, 1.0
    result, columns = run(OSCILLATOR.format(formulation=formulation))
    omega = math.sqrt(k / inertia)
    switches = result.metadata["friction_switches"]
    # closed form: each half cycle is a free oscillation about +-Tc/k, half a period long,
    # and its amplitude about 0 falls by 2 Tc / k: 1, -0.7, 0.4, then -0.1 where it sticks
    # (|k angle| = 1 <= Ts = Tc)
    turns = [(-1) ** n * (a0 - 2 * n * tc / k) for n in range(1, 4)]
    assert [s["mode"] for s in switches] == [1, -1, 0]
    times = np.array([s["t"] for s in switches])
    # the switch times are the located zero crossings of the rate: to the run's rtol
    np.testing.assert_allclose(times, np.arange(1, 4) * math.pi / omega, rtol=1e-8, atol=0)
    t = np.array(result.times)
    angle = columns["pivot.angle"]
    at_switch = np.array([angle[np.argmin(np.abs(t - s))] for s in times])
    # amplitudes to 1e-8 (the brief's bound; the integration error at rtol 1e-10 is below it)
    np.testing.assert_allclose(at_switch, turns, rtol=0, atol=1e-8)
    stuck = t > times[-1]  # the switch row itself ends the sliding segment
    assert abs(angle[-1]) < tc / k
    # no creep: the stuck coordinate is held by a row, to roundoff
    assert np.max(np.abs(angle[stuck] - angle[stuck][0])) < 1e-12
    assert np.all(columns["pivot.friction_mode"][stuck] == 0)
    # the holding torque balances the spring exactly: -(-k angle)
    np.testing.assert_allclose(columns["pivot.friction"][stuck], k * angle[stuck], rtol=1e-9,
                               atol=1e-12)  # the multiplier to the solver's precision
    sliding = ~stuck
    np.testing.assert_allclose(np.abs(columns["pivot.friction"][sliding]), tc, rtol=1e-12,
                               atol=0)  # the law's constant, exactly


@pytest.mark.parametrize("joint", ["translational", "cylindrical"])
def test_block_on_incline_within_the_friction_cone_does_not_move(joint):
    theta, mu, m, g = 0.3, 0.5, 2.0, 9.81
    assert math.tan(theta) < mu
    result, columns = run(INCLINE.format(theta=theta, mu=mu).replace("translational", joint))
    s = columns["slide.displacement"]
    assert np.max(np.abs(s)) < 1e-9
    assert np.all(columns["slide.friction_mode"] == 0)
    # the friction holds the block: m g sin(theta) up the slope (the axis points down it)
    np.testing.assert_allclose(columns["slide.friction"], -m * g * math.sin(theta), rtol=1e-9,
                               atol=0)  # a multiplier, solved to roundoff
    assert result.metadata["friction_switches"] == []


@pytest.mark.parametrize("joint", ["translational", "cylindrical"])
def test_block_on_steep_incline_slides_with_coulomb_deceleration(joint):
    theta, mu, m, g = 0.6, 0.5, 2.0, 9.81
    assert math.tan(theta) > mu
    result, columns = run(INCLINE.format(theta=theta, mu=mu).replace("translational", joint))
    t = np.array(result.times)
    a = g * (math.sin(theta) - mu * math.cos(theta))
    # closed form s = a t^2 / 2 from rest; the integrator's error at rtol 1e-10 is far below
    np.testing.assert_allclose(columns["slide.displacement"], 0.5 * a * t ** 2, rtol=1e-8,
                               atol=1e-10)
    np.testing.assert_allclose(columns["slide.friction"], -mu * m * g * math.cos(theta),
                               rtol=1e-12, atol=0)  # the law's constant


@pytest.mark.parametrize(("joint", "friction", "expected"), [
    ("revolute", "{coulomb: 2, static: 1}", ("E103", "joints[0].friction.static")),
    ("translational", "{coulomb: -1}", ("E103", "joints[0].friction.coulomb")),
    ("cylindrical", "{viscous: -2}", ("E103", "joints[0].friction.viscous")),
    ("revolute", "{coulomb: 1, slip: 2}", ("E101", "joints[0].friction.slip")),
])
def test_bad_friction_is_located(joint, friction, expected):
    text = INCLINE.format(theta=0.3, mu=0.5).replace("translational", joint).replace(
        "friction: {coulomb: mu * m * g * cos(theta)}", f"friction: {friction}")
    with pytest.raises(ModelError) as raised:
        casmech.loads(text)
    found = [(d.code, d.path) for d in raised.value.diagnostics]
    assert found == [expected]
    assert raised.value.diagnostics[0].source.line == 14  # the friction's line


def test_run_writes_the_holding_force_and_the_switches(tmp_path, monkeypatch):
    """`casmech run`: the streamed results.csv holds the stuck joint's holding force (not the
    bundle's law at rest, 0), metadata.json the switches."""
    import json

    import pandas as pd

    from casmech.cli import main

    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))
    model = tmp_path / "oscillator.yaml"
    model.write_text(OSCILLATOR.format(formulation="auto"))
    assert main(["run", str(model), "--out", str(tmp_path / "out")]) == 0
    table = pd.read_csv(tmp_path / "out" / "results.csv")
    stuck = table[table["pivot.friction_mode"] == 0]
    assert len(stuck) > 50
    # held against the spring: friction = k angle (k = 10), as the closed form's stuck state
    np.testing.assert_allclose(stuck["pivot.friction"], 10.0 * stuck["pivot.angle"], rtol=1e-9,
                               atol=1e-12)  # the multiplier to the solver's precision
    metadata = json.loads((tmp_path / "out" / "metadata.json").read_text())
    assert [s["mode"] for s in metadata["result"]["friction_switches"]] == [1, -1, 0]


def double_pendulum(t_end: float) -> str:
    """models/double_pendulum.yaml with friction in both joints (the elbow stuck at first,
    needing a holding torque only once the pivot slides)."""

    text = (MODELS / "double_pendulum.yaml").read_text()
    text = text.replace("    axis: [0, 1, 0]\n  - name: elbow", "    axis: [0, 1, 0]\n"
                        "    friction: {coulomb: 2.0, viscous: 0.1, static: 2.5}\n"
                        "  - name: elbow")
    text = text.replace("    at: [-L1 * sin(theta1), 0, -L1 * cos(theta1)]\n    axis: [0, 1, 0]\n",
                        "    at: [-L1 * sin(theta1), 0, -L1 * cos(theta1)]\n    axis: [0, 1, 0]\n"
                        "    friction: {coulomb: 0.2, static: 0.3}\n")
    assert text.count("friction:") == 2
    return text.replace("t_end: 2\n", f"t_end: {t_end}\n").replace(
        "rtol: 1.0e-8", "rtol: 1.0e-10").replace("atol: 1.0e-10", "atol: 1.0e-12")


def test_double_pendulum_with_friction_dissipates_and_holds_within_the_static_limit():
    result, columns = run(double_pendulum(1.0))
    switches = result.metadata["friction_switches"]
    assert result.metadata["friction_start_modes"]["elbow"] != 0  # released at the start
    assert len(switches) >= 3
    energy = columns["energy"]
    # friction never adds energy (a rise up to the integration error at rtol 1e-10)
    assert np.max(np.diff(energy)) < 1e-9 * np.max(np.abs(energy))
    assert energy[-1] < energy[0] - 1.0  # and it removes some
    for name, (tc, c, ts) in {"pivot": (2.0, 0.1, 2.5), "elbow": (0.2, 0.0, 0.3)}.items():
        mode, force = columns[f"{name}.friction_mode"], columns[f"{name}.friction"]
        rate = columns[f"{name}.angle_dot"]
        stuck, sliding = mode == 0, mode != 0
        assert np.all(np.abs(force[stuck]) <= ts * (1 + 1e-9))
        # sliding: the law with the segment's sign, which is the rate's wherever it moves
        np.testing.assert_allclose(force[sliding], -mode[sliding] * tc - c * rate[sliding],
                                   rtol=1e-12, atol=1e-12)  # the law itself
        moving = sliding & (np.abs(rate) > 1e-6)
        assert np.all(np.sign(rate[moving]) == mode[moving])


@pytest.mark.slow
def test_double_pendulum_with_friction_switches_alike_in_both_formulations():
    joint, _ = run(double_pendulum(1.0).replace("atol: 1.0e-12", "atol: 1.0e-12\n  "
                                                 "formulation: joint"))
    rp, _ = run(double_pendulum(1.0).replace("atol: 1.0e-12", "atol: 1.0e-12\n  "
                                              "formulation: rp"))
    a, b = joint.metadata["friction_switches"], rp.metadata["friction_switches"]
    assert [(s["joint"], s["mode"]) for s in a] == [(s["joint"], s["mode"]) for s in b]
    # two formulations of the same motion: switch times to the runs' tolerance
    np.testing.assert_allclose([s["t"] for s in a], [s["t"] for s in b], rtol=1e-8, atol=0)


def test_a_driven_joint_never_sticks_and_its_actuation_overcomes_the_friction():
    """On a driven coordinate the driver holds the joint: the friction is the sliding law by
    the prescribed rate, and the driver's torque (in the reaction) supplies exactly it."""

    text = (MODELS / "me751_pendulum.yaml").read_text()
    with_friction = text.replace("      angle: pi/4 * cos(2*t)\n",
                                 "      angle: pi/4 * cos(2*t)\n    friction: {coulomb: 3.0}\n")
    tables = []
    for model in (text, with_friction):
        functions = casmech.compile(casmech.loads(model))
        result = casmech.analyze(functions, analysis="dynamics", t_end=1.0)
        names, values = results_table(functions, result)
        tables.append(dict(zip(names, values.T, strict=True)))
    plain, rough = tables
    rate = rough["pivot.angle_dot"]
    moving = np.abs(rate) > 1e-9
    np.testing.assert_allclose(rough["pivot.friction"][moving], -3.0 * np.sign(rate[moving]),
                               rtol=0, atol=1e-12)  # the law's constant
    # the pivot's axis is x: its torque about x carries the actuation
    np.testing.assert_allclose(rough["pivot.tx"] - plain["pivot.tx"], -rough["pivot.friction"],
                               rtol=0, atol=1e-9)  # two inverse solves of the same motion


def test_a_cancelled_run_keeps_the_rows_of_its_finished_segments():
    from casmech.errors import Interrupted
    from casmech.runtime.cancel import CancelToken

    functions = casmech.compile(casmech.loads(OSCILLATOR.format(formulation="joint")))
    token = CancelToken()

    def progress(t):
        if t > 1.0:  # after the first switch (t = pi / sqrt(20) = 0.70)
            token.cancel()

    with pytest.raises(Interrupted) as raised:
        casmech.analyze(functions, progress=progress, token=token)
    partial = raised.value.partial
    assert 0.7 < partial.times[-1] <= 3.0
    assert partial.lam.shape[1] == functions.n_rows  # the base bundle's multipliers
    names, values = results_table(functions, partial)
    assert np.isfinite(values).all()


def test_purely_viscous_friction_is_a_damper_without_modes():
    """viscous only: the same motion as an rsda damper of the same c, and no switching."""
    text = OSCILLATOR.format(formulation="joint").replace("friction: {coulomb: Tc}",
                                                          "friction: {viscous: 0.8}")
    damper = OSCILLATOR.format(formulation="joint").replace(
        "    friction: {coulomb: Tc}\n", "").replace("stiffness: k}", "stiffness: k, damping: 0.8}")
    result, columns = run(text)
    _, reference = run(damper)
    assert "friction_switches" not in result.metadata
    # the same ODE written two ways, integrated at rtol 1e-10
    np.testing.assert_allclose(columns["pivot.angle"], reference["pivot.angle"], rtol=0,
                               atol=1e-8)
    np.testing.assert_allclose(columns["pivot.friction"], -0.8 * columns["pivot.angle_dot"],
                               rtol=1e-12, atol=1e-14)  # the law itself
