"""The multipliers of r-p / r-omega dynamics rows (reactions and a driver's actuation) are solved
at each row's state (runtime.dae_rows.solve), and the joint formulation's loop rows by default
(`solver: {loop_rows: solved}`, runtime.joint_rows), so they are as accurate as the state:
against inverse dynamics of the same motion, the other formulations, and the closed form of a
driven block whose Coulomb friction reverses between two output rows."""

from __future__ import annotations

import numpy as np
import pytest

import casmech
from casmech.api import results_table
from tests.conftest import MODELS

CRANK_JOINTS = ("crank_pivot", "crank_pin", "wrist_pin", "slide")
INTEGRATOR = {"loop_rows": "integrator"}  # the joint loop rows from IDAS's algebraic states
COMPONENTS = ("fx", "fy", "fz", "tx", "ty", "tz")

BLOCK = """casmech: 1
name: driven_block
parameters: {{m: 2.0, A: 0.1, w: 3.0, Fc: 1.5}}
gravity: [0, 0, 0]
bodies:
  - {{name: block, mass: m, inertia: [0.1, 0.1, 0.1], position: [0, 0, 0]}}
joints:
  - name: slide
    type: translational
    body_i: ground
    body_j: block
    at: [0, 0, 0]
    axis: [1, 0, 0]
    driver: {{displacement: A * sin(w * t)}}
    friction: {{coulomb: Fc}}
analysis: {{type: dynamics, t_end: 1.0, output_step: 0.01, rtol: {rtol}, atol: 1.0e-12,
           formulation: {formulation}}}
"""


def _columns(functions, result) -> dict[str, np.ndarray]:
    names, values = results_table(functions, result)
    return dict(zip(names, values.T, strict=True))


@pytest.fixture(scope="module")
def crank():
    """The driven slider-crank over 0.5 s (a half turn): inverse dynamics, and dynamics in
    each formulation at rtol 1e-10 (joint: its loop rows solved, the default; joint_z: from
    IDAS's algebraic states; both on IDAS, method bdf: one integration read two ways), and r-p
    at rtol 1e-12 (rp_tight)."""
    functions = casmech.compile(casmech.load(MODELS / "slider_crank.yaml"))
    runs = {"inverse": casmech.analyze(functions, analysis="inverse_dynamics", t_end=0.5)}
    for name, formulation, options in (("rp", "rp", None), ("romega", "romega", None),
                                       ("joint", "joint", None),
                                       ("joint_z", "joint", INTEGRATOR)):
        method = "bdf" if formulation == "joint" else "auto"
        runs[name] = casmech.analyze(functions, analysis="dynamics", formulation=formulation,
                                     method=method, t_end=0.5, rtol=1e-10, atol=1e-12,
                                     options=options)
    runs["rp_tight"] = casmech.analyze(functions, analysis="dynamics", formulation="rp",
                                       t_end=0.5, rtol=1e-12, atol=1e-14)
    return {name: _columns(functions, result) for name, result in runs.items()}


def _reactions(columns: dict[str, np.ndarray]) -> np.ndarray:
    return np.array([columns[f"{joint}.{c}"] for joint in CRANK_JOINTS for c in COMPONENTS])


@pytest.mark.parametrize("formulation", ["rp", "romega", "joint"])
def test_a_driven_slider_cranks_actuation_and_reactions_are_inverse_dynamics(crank, formulation):
    """The motion is fully driven, so dynamics and inverse dynamics are one motion: the crank
    torque and every reaction agree to the state's accuracy."""
    rows, reference = crank[formulation], crank["inverse"]
    np.testing.assert_allclose(rows["t"], reference["t"], rtol=0, atol=1e-12)  # one grid
    scale = np.abs(_reactions(reference)).max()
    # the rows' multipliers are an exact solve at states within ~rtol 1e-10 of the motion;
    # 1e-9 of the largest value leaves 10x for the condition of that solve
    np.testing.assert_allclose(rows["crank_pivot.tz"], reference["crank_pivot.tz"], rtol=0,
                               atol=1e-9 * np.abs(reference["crank_pivot.tz"]).max())
    np.testing.assert_allclose(_reactions(rows), _reactions(reference), rtol=0,
                               atol=1e-9 * scale)  # as above, every joint's six columns


@pytest.mark.parametrize("formulation", ["rp", "romega"])
def test_a_driven_slider_cranks_reactions_are_the_joint_formulations(crank, formulation):
    """The joint formulation's loop multipliers are solved at each row's state too
    (runtime.joint_rows): its rows and the body formulations' agree as each does with
    inverse dynamics."""
    scale = np.abs(_reactions(crank["joint"])).max()
    # two integrations of one motion at rtol 1e-10, each row an exact solve at its state:
    # 1e-9 of the largest reaction leaves 10x for the two solves' conditions
    np.testing.assert_allclose(_reactions(crank[formulation]), _reactions(crank["joint"]),
                               rtol=0, atol=1e-9 * scale)


def test_a_joint_runs_integrator_loop_rows_are_within_its_error(crank):
    """With loop_rows: integrator the joint loop rows read IDAS's algebraic states: the run's
    states are the solved run's, its reactions within IDAS's interpolation of them (out of its
    error test) of inverse dynamics."""
    for column in ("slider.x", "slider.vx", "crank.e0"):  # one integration, two readings
        np.testing.assert_array_equal(crank["joint_z"][column], crank["joint"][column])
    scale = np.abs(_reactions(crank["inverse"])).max()
    # measured 4.9e-8 of the largest reaction at rtol 1e-10 (docs/decisions/row-multipliers.md)
    np.testing.assert_allclose(_reactions(crank["joint_z"]), _reactions(crank["inverse"]),
                               rtol=0, atol=1e-7 * scale)


def test_a_joint_runs_default_loop_rows_are_nearer_a_tight_rp_run_than_the_integrators(crank):
    """The default joint rows (loop multipliers solved at each row's state) are nearer the r-p
    run at rtol 1e-12 (a second formulation, 100x tighter) than the same integration's rows
    read from IDAS's algebraic states: every reaction and the crank torque."""
    reference = crank["rp_tight"]

    def error(rows: dict[str, np.ndarray]) -> tuple[float, float]:
        return (np.abs(_reactions(rows) - _reactions(reference)).max(),
                np.abs(rows["crank_pivot.tz"] - reference["crank_pivot.tz"]).max())

    solved, integrator = error(crank["joint"]), error(crank["joint_z"])
    for a, b in zip(solved, integrator, strict=True):
        # the solved rows' error is the states' (rtol 1e-10); IDAS's interpolated algebraic
        # states are out of its error test, far less accurate (docs/decisions/row-multipliers.md)
        assert a * 10 < b, (solved, integrator)


def _planar_four_bar() -> str:
    """models/four_bar.yaml with its pins revolute about z: a planar loop whose cut joint's
    out-of-plane rows depend on the tree's (the joint DAE masks them; r-p drops them)."""
    text = (MODELS / "four_bar.yaml").read_text()
    for old in ("type: spherical\n", "type: universal\n"):
        assert old in text
        text = text.replace(old, "type: revolute\n")
    text = text.replace("    at: [0, a, 0]\n", "    at: [0, a, 0]\n    axis: [0, 0, 1]\n")
    return "\n".join(line for line in text.splitlines() if "axis_i" not in line
                     and "axis_j" not in line).replace(
        "    at: [Cx, Cy, 0]\n", "    at: [Cx, Cy, 0]\n    axis: [0, 0, 1]\n")


def test_a_planar_four_bars_joint_rows_with_masked_loop_rows_are_inverse_dynamics():
    """The driven planar four-bar in the joint formulation: the loop rows it masks are solved
    as lam_k = P_k u_dot - gamma_k (0), the reactions reported as the least-norm ones; the
    crank torque (unique) is inverse dynamics' and every reaction the r-p run's and inverse
    dynamics' least-norm ones."""
    functions = casmech.compile(casmech.loads(_planar_four_bar()))
    reference = _columns(functions, casmech.analyze(functions, analysis="inverse_dynamics",
                                                   t_end=0.3))
    runs = {name: casmech.analyze(functions, analysis="dynamics", formulation=name,
                                  t_end=0.3, rtol=1e-10, atol=1e-12)
            for name in ("joint", "rp")}
    assert runs["joint"].metadata["dropped_rows"] == 3  # the out-of-plane rows
    rows = {name: _columns(functions, run) for name, run in runs.items()}
    joints = ("crank_pivot", "coupler_pin", "rocker_pin", "rocker_pivot")

    def reactions(columns):
        return np.array([columns[f"{j}.{c}"] for j in joints for c in COMPONENTS])

    scale = np.abs(reactions(reference)).max()
    torque = reference["crank_pivot.tz"]
    # as for the slider-crank: rows solved at states within ~rtol 1e-10 of the driven motion
    np.testing.assert_allclose(rows["joint"]["crank_pivot.tz"], torque, rtol=0,
                               atol=1e-9 * np.abs(torque).max())
    np.testing.assert_allclose(reactions(rows["joint"]), reactions(reference), rtol=0,
                               atol=1e-9 * scale)  # as above, every least-norm reaction
    np.testing.assert_allclose(reactions(rows["joint"]), reactions(rows["rp"]), rtol=0,
                               atol=1e-9 * scale)  # two integrations, as above


@pytest.mark.parametrize("formulation", ["rp", "romega"])
@pytest.mark.parametrize("rtol", [1e-6, 1e-10])
def test_a_driven_blocks_force_is_the_closed_form_also_right_after_the_friction_reverses(
        formulation, rtol):
    """x = A sin(w t) driven, Coulomb friction Fc: the driver's force on the block is
    m x_ddot + Fc sign(x_dot) at every row. The rate reverses at t = pi / (2 w) = 0.5236,
    between the rows 0.52 and 0.53, within one of the integrator's steps."""
    m, amplitude, w, coulomb = 2.0, 0.1, 3.0, 1.5
    functions = casmech.compile(casmech.loads(BLOCK.format(rtol=rtol, formulation=formulation)))
    rows = _columns(functions, casmech.analyze(functions))
    t = rows["t"]
    force = (m * -amplitude * w**2 * np.sin(w * t)
             + coulomb * np.sign(amplitude * w * np.cos(w * t)))
    assert np.any(np.diff(np.sign(rows["slide.displacement_dot"])) != 0)  # it reverses
    # the reaction is what the joint exerts on the block, the driving force with it. The
    # driven state is exact, so is the solve at it: roundoff of one body's small system
    np.testing.assert_allclose(rows["slide.fx"], force, rtol=0, atol=1e-12)


def test_a_joint_event_rows_reactions_are_inverse_dynamics_at_the_event():
    """The event row of the driven slider-crank in the joint formulation (the slider passing
    x = 2) is solved at its own state too (the default loop_rows): its reactions and crank
    torque are inverse dynamics' at the event's time."""
    text = (MODELS / "slider_crank.yaml").read_text().replace(
        "analysis:", 'events:\n  - {name: mid, when: "slider.x - 2.0"}\nanalysis:', 1)
    functions = casmech.compile(casmech.loads(text))
    frame = casmech.analyze(functions, analysis="dynamics", formulation="joint", t_end=0.5,
                            rtol=1e-10, atol=1e-12).events_dataframe()
    assert frame["name"].tolist() == ["mid"]
    t_event = float(frame["t"].iloc[0])
    reference = _columns(functions, casmech.analyze(
        functions, analysis="inverse_dynamics", t_end=t_event, output_step=t_event))
    assert reference["t"][-1] == pytest.approx(t_event, rel=1e-14, abs=0)
    names = [f"{joint}.{c}" for joint in CRANK_JOINTS for c in COMPONENTS]
    row = frame[names].to_numpy(float)[0]
    expected = np.array([reference[name][-1] for name in names])
    # the event's state lies on the driven motion to the integrator's accuracy over the
    # short located step, and the row is an exact solve at it: 1e-11 of the largest value
    np.testing.assert_allclose(row, expected, rtol=0, atol=1e-11 * np.abs(expected).max())
