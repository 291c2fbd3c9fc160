"""Force laws that read the state (equations/coordinates.py) against closed forms and against the
same law written as a tsda or rsda (a second formulation of the same physics)."""

from __future__ import annotations

import numpy as np
import pytest

import casmech
from tests.conftest import Table

FREE = """
casmech: 1
name: drag
parameters: {m: 2.0, c: 3.0}
gravity: [0, 0, 0]
bodies:
  - {name: bar, mass: m, inertia: [0.1, 0.2, 0.25], position: [0.5, 0, 0],
     velocity: [1.5, -0.5, 0.25]}
forces:
  - {name: drag, type: force, body: bar, value: ["-c*bar.vx", "-c*bar.vy", "-c*bar.vz"]}
"""

PIVOT = """
casmech: 1
name: torsion
parameters: {k: 3.0, J: 0.5}
gravity: [0, 0, -9.81]
bodies:
  - {name: bar, mass: 1, inertia: [0.3, 0.3, J], position: [0, 0, 0],
     angular_velocity: [0, 0, 1.2]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 0, 1]}
forces:
"""


def run(text: str, t_end: float, step: float = 0.01, **settings) -> Table:
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions, "dynamics", t_end=t_end, output_step=step, **settings)
    return Table(*casmech.results_table(functions, result))


TIGHT = {"rtol": 1e-10, "atol": 1e-12}


def test_linear_drag_on_the_velocity_decays_exponentially():
    """m v' = -c v: v = v0 exp(-c t/m), x = x0 + v0 (m/c)(1 - exp(-c t/m))."""
    table = run(FREE, t_end=1.0, **TIGHT)
    t, v0 = table["t"], np.array([1.5, -0.5, 0.25])
    decay = np.exp(-3.0 * t / 2.0)
    velocity = np.column_stack([table[f"bar.v{a}"] for a in "xyz"])
    position = np.column_stack([table[f"bar.{a}"] for a in "xyz"])
    # IDAS at rtol 1e-10: measured 6.9e-10 m/s and 4.6e-10 m
    np.testing.assert_allclose(velocity, np.outer(decay, v0), rtol=0, atol=5e-9)
    np.testing.assert_allclose(position, [0.5, 0, 0] + np.outer((1 - decay) * 2 / 3, v0),
                               rtol=0, atol=5e-9)


def test_torque_minus_k_angle_is_a_harmonic_oscillator():
    """No torque from gravity about a vertical axis: J angle'' = -k angle, so with angle(0) = 0
    and rate w0, angle = (w0/omega) sin(omega t), period 2 pi sqrt(J/k)."""
    text = PIVOT + '  - {name: law, type: torque, body: bar, value: [0, 0, "-k*pivot.angle"]}\n'
    table = run(text, t_end=2.0, **TIGHT)
    omega = np.sqrt(3.0 / 0.5)
    angle = 2 * np.arctan2(table["bar.e3"], table["bar.e0"])
    # IDAS at rtol 1e-10: measured 5.1e-10 rad on a 0.49 rad amplitude
    np.testing.assert_allclose(angle, 1.2 / omega * np.sin(omega * table["t"]), rtol=0,
                               atol=5e-9)
    crossings = table["t"][1:][np.diff(np.sign(table["bar.wz"])) != 0]  # rate's zeros: T/2 apart
    assert np.ptp(np.diff(crossings)) < 0.02 and abs(crossings[0] - np.pi / 2 / omega) < 0.01


def test_force_on_a_slide_displacement_is_harmonic():
    """A block on a tilted translational joint, pulled back by -k displacement - c rate: the
    damped oscillator x'' + (c/m) x' + (k/m) x = 0 from x(0) = 0, x'(0) = u."""
    text = """
casmech: 1
name: slide
parameters: {k: 50.0, c: 2.0}
gravity: [0, 0, 0]
bodies:
  - {name: block, mass: 2, inertia: [0.1, 0.1, 0.1], position: [0, 0, 0],
     velocity: [0.3, 0.6, 0.6]}
joints:
  - {name: slide, type: translational, body_i: ground, body_j: block, at: [0, 0, 0],
     axis: [1, 2, 2]}
forces:
  - {name: law, type: force, body: block,
     value: ["f/3", "2*f/3", "2*f/3"]}
"""
    text = text.replace("f/3", "(-k*slide.displacement - c*slide.displacement_dot)/3")
    table = run(text, t_end=1.0, **TIGHT)
    t, u = table["t"], 0.9  # the initial speed along the unit axis [1, 2, 2]/3
    sigma, omega = 0.5, np.sqrt(25 - 0.25)
    exact = u / omega * np.exp(-sigma * t) * np.sin(omega * t)
    along = np.column_stack([table[f"block.{a}"] for a in "xyz"]) @ (np.array([1, 2, 2]) / 3)
    # IDAS at rtol 1e-10: measured 3.3e-10 m on a 0.16 m amplitude
    np.testing.assert_allclose(along, exact, rtol=0, atol=3e-9)


def _compare(first: Table, second: Table, atol: float, skip=("energy",)) -> None:
    """Every column but `skip` equal within atol."""
    assert first.names == second.names
    keep = [k for k, name in enumerate(first.names) if name not in skip]
    np.testing.assert_allclose(first.values[:, keep], second.values[:, keep], rtol=0, atol=atol)


def test_rsda_equals_the_same_law_written_as_a_torque():
    """A spring-damper with an actuator on a tilted hinge under gravity: rsda(k, c, actuator),
    whose tension k (angle - free) + c angle_dot + actuator resists the angle, and a torque
    value -(tension) about the axis give the same results, every column but the energy (the
    rsda's spring potential is in it, a torque's is not)."""
    hinge = PIVOT.replace("axis: [0, 0, 1]", "axis: [0, 0.6, 0.8]").replace(
        "position: [0, 0, 0]", "position: [0.4, 0, 0]")
    rsda = hinge + ('  - {name: law, type: rsda, joint: pivot, stiffness: k, damping: 0.2,\n'
                    '     free_angle: 0.1, actuator: "0.5*sin(3*t)"}\n')
    law = "(k*(0.1 - pivot.angle) - 0.2*pivot.angle_dot - 0.5*sin(3*t))"
    torque = hinge + (f'  - {{name: law, type: torque, body: bar,\n'
                      f'     value: ["0", "0.6*{law}", "0.8*{law}"]}}\n')
    first, second = run(rsda, t_end=1.0, **TIGHT), run(torque, t_end=1.0, **TIGHT)
    # the same equations, rounded differently, so IDAS steps differ slightly: measured at
    # rtol 1e-10 6.6e-10 in positions and velocities, 1.6e-7 in accelerations and reactions
    _compare(first, second, atol=2e-6)
    np.testing.assert_allclose(first.values[:, 1:14], second.values[:, 1:14], rtol=0, atol=1e-8)
    angle = 2 * np.arctan2(0.6 * first["bar.e2"] + 0.8 * first["bar.e3"], first["bar.e0"])
    spring = 0.5 * 3.0 * (angle - 0.1) ** 2  # the rsda's potential, in its energy only
    # measured 1.8e-9 J (energies ~1 J)
    np.testing.assert_allclose(first["energy"] - second["energy"], spring, rtol=0, atol=1e-8)


def test_tsda_equals_the_same_law_written_as_a_force_of_body_states():
    """A spring pendulum (free body on a tsda to the origin, gravity): the tsda and a force
    -(k (L - l0) + c L') (r / L) with L = |r| written from bar.x .. bar.vz agree."""
    body = """
casmech: 1
name: spring_pendulum
parameters: {k: 40.0, c: 0.3, l0: 0.8}
bodies:
  - {name: bar, mass: 1.5, inertia: [0.02, 0.02, 0.02], position: [0.5, 0.2, -0.9],
     velocity: [0.1, 0.4, 0]}
forces:
"""
    tsda = body + ("  - {name: spring, type: tsda, body_i: ground, at_i: [0, 0, 0], body_j: bar,\n"
                   "     at_j: [0.5, 0.2, -0.9], stiffness: k, damping: c, free_length: l0}\n")
    length = "sqrt(bar.x**2 + bar.y**2 + bar.z**2)"
    rate = f"(bar.x*bar.vx + bar.y*bar.vy + bar.z*bar.vz)/{length}"
    tension = f"(k*({length} - l0) + c*{rate})/{length}"
    force = body + (f'  - {{name: spring, type: force, body: bar,\n     value: ["-{tension}*bar.x",'
                    f' "-{tension}*bar.y", "-{tension}*bar.z"]}}\n')
    first, second = run(tsda, t_end=1.0), run(force, t_end=1.0)
    # the same law, differently rounded; IDAS took the same steps: measured 8.7e-13
    _compare(first, second, atol=1e-10)
    length = np.sqrt(sum(first[f"bar.{a}"] ** 2 for a in "xyz"))
    spring = 0.5 * 40.0 * (length - 0.8) ** 2  # the tsda's potential, in its energy only
    # measured 1.7e-14 J on energies ~12 J
    np.testing.assert_allclose(first["energy"] - second["energy"], spring, rtol=0, atol=1e-10)


def test_actuator_reading_the_body_spin_equals_rsda_damping():
    """An rsda actuator -c*bar.wz on a vertical hinge from ground is the rsda's damping c."""
    damped = PIVOT + "  - {name: law, type: rsda, joint: pivot, stiffness: k, damping: 0.4}\n"
    actuated = PIVOT + ('  - {name: law, type: rsda, joint: pivot, stiffness: k,\n'
                        '     actuator: "0.4*bar.wz"}\n')
    first, second = run(damped, t_end=1.0, **TIGHT), run(actuated, t_end=1.0, **TIGHT)
    # tension = k angle + c angle_dot + actuator, and bar.wz = angle_dot here, differently
    # rounded: at rtol 1e-10 measured 6.6e-11 in positions and rates, 1.6e-8 at most in the
    # accelerations (solved at each row's state from positions and rates of that rounding: the
    # noisiest columns)
    np.testing.assert_allclose(first.values[:, 1:14], second.values[:, 1:14], rtol=0, atol=1e-8)
    _compare(first, second, atol=2e-6, skip=())


def test_force_law_reaches_the_sensitivities():
    """d(bar.vx at t)/dc of the drag model, exact by IDAS forward sensitivities, equals the
    closed form d/dc [v0 exp(-c t/m)] = -(t/m) v0 exp(-c t/m)."""
    from casmech.optimal.sensitivity import sensitivity

    model = casmech.loads(FREE)
    times = [0.3, 0.8]
    result = sensitivity(model, ["c"], ["bar.vx"], times, mode="forward")
    exact = [-(t / 2.0) * 1.5 * np.exp(-3.0 * t / 2.0) for t in times]
    # IDAS sensitivities at the default tolerances: measured 1.1e-10
    np.testing.assert_allclose(np.ravel(result.jacobian), exact, rtol=1e-6, atol=1e-8)


@pytest.mark.parametrize("angle", [0.2, -2.5])
def test_joint_angle_is_measured_from_the_files_pose(angle):
    """A hinge built at a turned pose: pivot.angle is 0 there (like a driver angle), so the
    state seen by the law at t = 0 is 0 whatever the pose, and a torque -k (angle - a) drives
    the bar to a."""
    turned = PIVOT.replace("position: [0, 0, 0]", "position: [0, 0, 0],\n     orientation: "
                           "{axis_angle: {axis: [0, 0, 1], angle: 0.7}}").replace(
        "angular_velocity: [0, 0, 1.2]", "angular_velocity: [0, 0, 0]")
    law = f"-k*(pivot.angle - ({angle})) - 2*pivot.angle_dot"
    table = run(turned + f'  - {{name: law, type: torque, body: bar, value: [0, 0, "{law}"]}}\n',
                t_end=8.0, step=0.1)
    final = 2 * np.arctan2(table["bar.e3"][-1], table["bar.e0"][-1])
    # damped to ~exp(-16) of the start: measured 2.9e-7 rad left
    np.testing.assert_allclose(final, np.angle(np.exp(1j * (0.7 + angle))), rtol=0, atol=1e-5)


COMPILED = """
casmech: 1
name: compiled_laws
parameters: {k: 3.0}
gravity: [0, 0, -9.81]
bodies:
  - {name: bar, mass: 1, inertia: [0.3, 0.3, 0.5], position: [0, 0, 0],
     angular_velocity: [0, 1.2, 0]}
  - {name: block, mass: 0.5, inertia: [0.01, 0.01, 0.01], position: [0.3, 0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 1, 0]}
forces:
  - {name: law, type: torque, body: bar, value: [0, "-k*pivot.angle - 0.1*bar.wy", 0]}
  - {name: mount, type: bushing, body_i: bar, body_j: block, at: [0.3, 0, 0],
     stiffness: [400, 400, 400], damping: [2, 2, 2], rotational_stiffness: [5, 5, 5]}
"""


def test_compiled_code_runs_the_laws_and_the_bushing_like_the_interpreted_one(tmp_path):
    """The C library built from a model with state-reading laws and a bushing gives the same
    motion as the interpreted CasADi functions."""
    from casmech.backends import codegen

    chain = codegen.Toolchain(flags=("-O0",))
    if not codegen.available(chain):
        pytest.skip(f"no C compiler '{chain.compiler}'")
    model = casmech.loads(COMPILED)
    tables = []
    for functions in (casmech.compile(model), codegen.compiled(model, chain, root=tmp_path)):
        # the index-1 DAE: the index-2 one (the default) turns last-bit differences between C
        # and the VM into other step choices (3e-8 apart at the default rtol 1e-8, measured)
        result = casmech.analyze(functions, "dynamics", t_end=0.3, output_step=0.01,
                                 stabilization="projection")
        tables.append(Table(*casmech.results_table(functions, result)))
    # the same expressions evaluated by C and by CasADi's virtual machine: identical (0.0) for
    # the gallery models bushing_mount and user_force_pendulum run both ways
    _compare(*tables, atol=1e-10, skip=())
    assert np.ptp(tables[0]["block.x"]) > 1e-3
