"""Couplings of joint coordinates (gear, rack_pinion, coupler, screw; issue 32 item 4) against
closed forms written here: the accelerations of a gear pair, a pinion and rack and a nut on a
lead screw and each reaction column; the gear pair in kinematics, inverse dynamics, statics and
modal against the same closed forms; a coupler against the gear it equals."""

import math

import numpy as np
import pytest

import casmech
from casmech.cli import main
from casmech.errors import AnalysisError, UsageError
from casmech.optimal.sensitivity import sensitivity
from tests.conftest import MODELS, Table

G = 9.81
J1, J2, R_GEAR, TORQUE = 0.5, 0.7, -2.5, 3.0


def gear_pair(coupling: str | None = None, forces: str = "", analysis: str = "",
              driver: str = "") -> str:
    """Two disks on vertical pins (gravity along the axes: no gravity torque), coupled by
    `coupling` (default: a gear of ratio R_GEAR)."""
    coupling = coupling or f"{{name: mesh, type: gear, joint_i: p1, joint_j: p2, ratio: {R_GEAR}}}"
    return f"""
casmech: 1
name: gear_pair
bodies:
  - {{name: d1, mass: 2.0, inertia: [0.3, 0.3, {J1}], position: [0, 0, 0]}}
  - {{name: d2, mass: 3.0, inertia: [0.4, 0.4, {J2}], position: [1, 0, 0]}}
joints:
  - {{name: p1, type: revolute, body_i: ground, body_j: d1, at: [0, 0, 0], axis: [0, 0, 1]{driver}}}
  - {{name: p2, type: revolute, body_i: ground, body_j: d2, at: [1, 0, 0], axis: [0, 0, 1]}}
  - {coupling}
forces:
  - {{name: drive, type: torque, body: d1, value: [0, 0, {TORQUE}]}}
{forces}
analysis: {{type: dynamics, t_end: 0.6, output_step: 0.1, rtol: 1e-11, atol: 1e-12{analysis}}}
"""


def run(text: str, analysis: str = "dynamics", **options) -> Table:
    functions = casmech.compile(casmech.loads(text))
    return Table(*casmech.results_table(functions, casmech.analyze(functions, analysis,
                                                                   **options)))


def _close(got, want, what: str) -> None:
    # the consistent initial accelerations and multipliers solve a linear system: round-off
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12, err_msg=what)


@pytest.mark.parametrize("formulation", ["rp", "romega", "joint", "auto"])
def test_gear_pair_accelerates_at_the_closed_form(formulation):
    """alpha_1 = T / (J1 + r^2 J2), alpha_2 = r alpha_1, the gear's torque on disk 2 J2
    alpha_2; the angles follow alpha t^2 / 2 while they stay inside a turn."""
    table = run(gear_pair(), formulation=formulation)
    alpha = TORQUE / (J1 + R_GEAR ** 2 * J2)
    _close(table["d1.alphaz"][0], alpha, "alpha_1")
    _close(table["d2.alphaz"][0], R_GEAR * alpha, "alpha_2")
    _close(table["mesh.torque"][0], J2 * R_GEAR * alpha, "gear torque")
    # the torque on disk 2 about its axis: the gear's reaction torque column there
    _close(table["mesh.tz"][0], J2 * R_GEAR * alpha, "reaction tz")
    t = table["t"]
    # integrated at rtol 1e-11: the angles to the integrator's tolerance
    np.testing.assert_allclose(table["p1.angle"], alpha * t ** 2 / 2, rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(table["p2.angle"], R_GEAR * alpha * t ** 2 / 2, rtol=1e-7,
                               atol=1e-10)
    assert table["constraint_violation"].max() <= 1e-9


def test_auto_runs_joint_coordinates_with_the_coupling_a_closure_row():
    """A coupled tree runs in joint coordinates under auto: the gear's row is the loop DAE's
    closure row (its joint among the cut ones), the tree's joints hold both disks."""
    functions = casmech.compile(casmech.loads(gear_pair()))
    result = casmech.analyze(functions, "dynamics")
    assert result.metadata["formulation"] == "joint"
    assert result.metadata["tree"] == ["p1", "p2"] and result.metadata["cut_joints"] == ["mesh"]


def test_auto_keeps_rp_for_a_screws_floating_nut():
    """A screw has no tree motion: its nut floats in the tree (a free joint held by the
    screw's five closure rows), where auto runs rp; `formulation: joint` runs it as asked."""
    functions = casmech.compile(casmech.loads(SCREW))
    assert casmech.analyze(functions, "dynamics").metadata["formulation"] == "rp"
    joint = casmech.analyze(functions, "dynamics", formulation="joint").metadata
    assert joint["tree"] == ["free 'nut'"] and joint["cut_joints"] == ["thread"]


def test_a_formulation_that_takes_no_couplings_refuses_them_by_name():
    from casmech.formulations.registry import FORMULATIONS
    from tests.unit.formulations.test_protocol import Baumgarte

    FORMULATIONS.register(Baumgarte("tree_only", takes_couplings=False))
    try:
        functions = casmech.compile(casmech.loads(gear_pair()))
        with pytest.raises(AnalysisError, match="joint 'mesh'") as error:
            casmech.analyze(functions, "dynamics", formulation="tree_only")
        assert "formulation: rp, romega, joint or auto" in str(error.value)
    finally:
        FORMULATIONS.unregister("tree_only")


def test_a_gear_on_a_cut_joint_in_joint_coordinates():
    """p2 `cut: true`: disk 2 floats in the tree (a free joint), held by p2's rows and the
    gear's row, both closure rows over its pose: the same closed form."""
    text = gear_pair().replace("axis: [0, 0, 1]}\n  - {name: mesh",
                               "axis: [0, 0, 1], cut: true}\n  - {name: mesh")
    assert "cut: true" in text
    table = run(text, formulation="joint")
    alpha = TORQUE / (J1 + R_GEAR ** 2 * J2)
    _close(table["d1.alphaz"][0], alpha, "alpha_1")
    _close(table["d2.alphaz"][0], R_GEAR * alpha, "alpha_2")
    _close(table["mesh.torque"][0], J2 * R_GEAR * alpha, "gear torque")


def test_a_coupler_is_the_gear_it_writes():
    """coefficients [-r, 1] over (p1, p2) is the gear of ratio r: the same motion, and its
    force column is the gear's torque (-lambda, the generalized force on p2's angle)."""
    gear = run(gear_pair())
    coupler = run(gear_pair(f"{{name: mesh, type: coupler, joints: [p2, p1.angle], "
                            f"coefficients: [1, {-R_GEAR}]}}"))
    # the same equations in another row order: round-off
    np.testing.assert_allclose(coupler["p2.angle"], gear["p2.angle"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(coupler["mesh.force"], gear["mesh.torque"], rtol=1e-9,
                               atol=1e-12)


def test_gear_pair_in_kinematics_and_inverse_dynamics():
    """p1 driven along alpha t^2 / 2: disk 2 turns r times as far (kinematics), and the torque
    the driver needs is the applied one's opposite (inverse dynamics: p1's tz + T = 0)."""
    alpha = TORQUE / (J1 + R_GEAR ** 2 * J2)
    driver = f", driver: {{angle: '{alpha / 2} * t**2'}}"
    kinematics = run(gear_pair(driver=driver), "kinematics")
    t = kinematics["t"]
    # assembly to its position tolerance
    np.testing.assert_allclose(kinematics["p2.angle"], R_GEAR * alpha * t ** 2 / 2, rtol=0,
                               atol=1e-10)
    inverse = run(gear_pair(driver=driver), "inverse_dynamics")
    # the applied torque is exactly what the prescribed motion needs: the driver holds 0
    np.testing.assert_allclose(inverse["p1.tz"], 0.0, rtol=0, atol=1e-9)
    _close(inverse["mesh.torque"], np.full(len(t), J2 * R_GEAR * alpha), "gear torque")


SPRING = "  - {name: spring, type: rsda, joint: p2, stiffness: 40.0}"


def test_gear_pair_statics_and_modal_with_a_spring_on_the_driven_disk():
    """A torsion spring k on disk 2: equilibrium T + r (-k theta_2) = 0 with theta_2 = r
    theta_1, so theta_1 = T / (k r^2); frequency omega^2 = k r^2 / (J1 + r^2 J2)."""
    k = 40.0
    statics = run(gear_pair(forces=SPRING), "statics")
    # the equilibrium to the statics tolerance
    np.testing.assert_allclose(statics["p1.angle"][-1], TORQUE / (k * R_GEAR ** 2), rtol=1e-9,
                               atol=1e-12)
    functions = casmech.compile(casmech.loads(gear_pair(forces=SPRING)))
    model = casmech.analyze(functions, "modal").linear_model
    omega = math.sqrt(k * R_GEAR ** 2 / (J1 + R_GEAR ** 2 * J2))
    # eigenvalues of the reduced linear model: round-off
    np.testing.assert_allclose(model.frequency_hz, [omega / (2 * math.pi)], rtol=1e-9, atol=0)


def test_check_counts_the_coupling_and_reports_a_redundant_one(tmp_path, capsys):
    """One DOF left by the gear; a second gear between the same joints is a redundant row,
    named by its joint and line."""
    path = tmp_path / "gears.yaml"
    path.write_text(gear_pair())
    assert main(["check", str(path)]) == 0
    assert "degrees of freedom: 1 " in capsys.readouterr().out
    twice = gear_pair().replace(
        "  - {name: mesh,", f"  - {{name: again, type: gear, joint_i: p1, joint_j: p2, "
        f"ratio: {R_GEAR}}}\n  - {{name: mesh,")
    path.write_text(twice)
    main(["check", str(path)])
    out = capsys.readouterr().out
    assert "degrees of freedom: 1 " in out
    line = twice.splitlines().index(next(x for x in twice.splitlines() if "name: mesh" in x)) + 1
    assert f"gears.yaml:{line}:" in out and "redundant" in out and "gear 'mesh'" in out


M_RACK, R_PINION, J_PINION = 4.0, 0.05, 0.002
RACK = f"""
casmech: 1
name: rack_and_pinion
bodies:
  - {{name: pinion, mass: 1.0, inertia: [0.001, 0.001, {J_PINION}], position: [0, 0, 0]}}
  - {{name: rack, mass: {M_RACK}, inertia: [0.01, 0.2, 0.2], position: [0, -{R_PINION}, 0]}}
joints:
  - {{name: shaft, type: revolute, body_i: ground, body_j: pinion, at: [0, 0, 0],
     axis: [0, 0, 1]}}
  - {{name: slide, type: translational, body_i: ground, body_j: rack, at: [0, -{R_PINION}, 0],
     axis: [-1, 0, 0]}}
  - {{name: teeth, type: rack_pinion, joint_i: shaft, joint_j: slide, radius: {R_PINION}}}
forces:
  - {{name: drive, type: torque, body: pinion, value: [0, 0, {TORQUE}]}}
analysis: {{type: dynamics, t_end: 1, output_step: 0.25, rtol: 1e-11, atol: 1e-12}}
"""


@pytest.mark.parametrize("formulation", ["rp", "romega", "joint", "auto"])
def test_pinion_and_rack_accelerate_at_the_closed_form_through_many_turns(formulation):
    """alpha = T / (J + m R^2), the rack's acceleration R alpha along its axis (-x) and the
    force on it m R alpha; after 1 s the pinion has turned 13 times, and the rack is where
    R alpha t^2 / 2 says (the row reads the angle by its sine and cosine)."""
    table = run(RACK, formulation=formulation)
    alpha = TORQUE / (J_PINION + M_RACK * R_PINION ** 2)
    _close(table["pinion.alphaz"][0], alpha, "alpha")
    _close(table["rack.ax"][0], -R_PINION * alpha, "rack acceleration")
    _close(table["teeth.force"][0], M_RACK * R_PINION * alpha, "rack force")
    # the force on the rack along its axis (-x): the reaction column's -fx
    _close(-table["teeth.fx"][0], M_RACK * R_PINION * alpha, "reaction fx")
    t = table["t"]
    # integrated at rtol 1e-11: positions to the integrator's tolerance
    np.testing.assert_allclose(table["slide.displacement"], R_PINION * alpha * t ** 2 / 2,
                               rtol=1e-7, atol=1e-10)
    assert R_PINION * alpha / 2 / R_PINION / (2 * math.pi) > 10  # turns made in the run
    assert table["constraint_violation"].max() <= 1e-8


M_NUT, J_NUT, LEAD = 0.5, 1e-4, 0.01
SCREW = f"""
casmech: 1
name: lead_screw
bodies:
  - {{name: nut, mass: {M_NUT}, inertia: [0.0002, 0.0002, {J_NUT}], position: [0, 0, 0.3]}}
joints:
  - {{name: thread, type: screw, body_i: ground, body_j: nut, at: [0, 0, 0.3], axis: [0, 0, 1],
     lead: {LEAD}}}
analysis: {{type: dynamics, t_end: 2, output_step: 0.5, rtol: 1e-11, atol: 1e-12}}
"""


@pytest.mark.parametrize("formulation", ["rp", "romega", "joint", "auto"])
def test_a_nut_falls_along_a_lead_screw_at_the_closed_form(formulation):
    """a = g m / (m + J (2 pi / L)^2) downwards, spinning at 2 pi a / L; the screw holds
    m (g - a) along the axis and J 2 pi a / L about it (the reaction columns)."""
    table = run(SCREW, formulation=formulation)
    a = G * M_NUT / (M_NUT + J_NUT * (2 * math.pi / LEAD) ** 2)
    spin = 2 * math.pi / LEAD
    _close(table["nut.az"][0], -a, "acceleration")
    _close(table["nut.alphaz"][0], -spin * a, "angular acceleration")
    _close(table["thread.fz"][0], M_NUT * (G - a), "axial force")
    _close(table["thread.tz"][0], -J_NUT * spin * a, "axial torque")
    t = table["t"]
    # integrated at rtol 1e-11: positions to the integrator's tolerance (about 40 turns)
    np.testing.assert_allclose(table["thread.displacement"], -a * t ** 2 / 2, rtol=1e-7,
                               atol=1e-10)
    assert table["constraint_violation"].max() <= 1e-8


def test_a_coupler_offset_shifts_the_relation():
    """`offset: o`: c . s = o, so the wheel stands at (o - c1 angle_1) / c2 in assembly with
    the pinion held at its file pose by a driver."""
    table = run(gear_pair("{name: mesh, type: coupler, joints: [p2, p1], coefficients: "
                          "[2.0, 1.0], offset: 0.3}", driver=", driver: {angle: '0'}"),
                "assembly")
    # assembly to its position tolerance
    np.testing.assert_allclose(table["p2.angle"][0], 0.15, rtol=0, atol=1e-10)


def test_the_sensitivity_to_the_ratio_is_the_closed_forms_derivative():
    """p2.angle(t) = r T / (J1 + r^2 J2) t^2 / 2, so d/dr = T (J1 - r^2 J2) / (J1 + r^2 J2)^2
    t^2 / 2 (forward and adjoint sensitivities through the coupling's row)."""
    text = gear_pair("{name: mesh, type: gear, joint_i: p1, joint_j: p2, ratio: r}").replace(
        "name: gear_pair\n", f"name: gear_pair\nparameters: {{r: {R_GEAR}}}\n")
    model = casmech.loads(text)
    want = TORQUE * (J1 - R_GEAR ** 2 * J2) / (J1 + R_GEAR ** 2 * J2) ** 2 * 0.5 ** 2 / 2
    for mode in ("forward", "adjoint"):
        found = sensitivity(model, ["r"], ["p2.angle"], [0.5], mode=mode)
        # IDAS with its sensitivities at rtol 1e-10
        np.testing.assert_allclose(found.jacobian[0, 0, 0], want, rtol=1e-7, atol=0,
                                   err_msg=mode)


def test_the_fmu_refuses_couplings_by_name(tmp_path):
    from casmech.fmu.start import start

    with pytest.raises(UsageError, match="couplings of joint coordinates \\('mesh'\\)"):
        start(casmech.loads(gear_pair()), ())


def test_a_gear_inside_a_component_couples_its_instances_joints():
    """Two instances of a gearbox component, ratios 2.5 and 2 (its default): each accelerates
    at its own T / (J1 + r^2 J2) (the coupling's joint names are the instance's)."""
    text = f"""
casmech: 1
name: two_gearboxes
components:
  box:
    parameters: {{r: 2.0}}
    bodies:
      - {{name: d1, mass: 2.0, inertia: [0.3, 0.3, {J1}], position: [0, 0, 0]}}
      - {{name: d2, mass: 3.0, inertia: [0.4, 0.4, {J2}], position: [1, 0, 0]}}
    joints:
      - {{name: p1, type: revolute, body_i: ground, body_j: d1, at: [0, 0, 0], axis: [0, 0, 1]}}
      - {{name: p2, type: revolute, body_i: ground, body_j: d2, at: [1, 0, 0], axis: [0, 0, 1]}}
      - {{name: mesh, type: gear, joint_i: p1, joint_j: p2, ratio: -r}}
    forces:
      - {{name: drive, type: torque, body: d1, value: [0, 0, {TORQUE}]}}
instances:
  - {{name: a, component: box, parameters: {{r: 2.5}}}}
  - {{name: b, component: box, position: [0, 3, 0]}}
analysis: {{type: dynamics, t_end: 0.2, output_step: 0.1}}
"""
    table = run(text)
    for instance, ratio in (("a", 2.5), ("b", 2.0)):
        alpha = TORQUE / (J1 + ratio ** 2 * J2)
        _close(table[f"{instance}.d1.alphaz"][0], alpha, instance)
        _close(table[f"{instance}.mesh.torque"][0], -J2 * ratio * alpha, instance)


def test_an_output_reads_the_gears_torque():
    """`outputs:` may read a coupling's column (N m for a gear's torque): twice the torque."""
    text = gear_pair().replace("analysis:", "outputs:\n  - {name: twice, value: "
                                            "'2 * mesh.torque'}\nanalysis:")
    table = run(text)
    # the same number doubled: round-off
    np.testing.assert_allclose(table["twice"], 2 * table["mesh.torque"], rtol=1e-15, atol=0)


@pytest.mark.parametrize("formulation", ["rp", "romega", "joint"])
def test_a_gear_of_whole_ratio_holds_through_many_turns(formulation):
    """Ratio -5/2 (integers 5 and 2 in its row): 5 s of the same torque turn disk 2 three times
    and disk 1 more than once, and both angles stay on alpha t^2 / 2 (the joint angles are in
    (-pi, pi]: compared modulo 2 pi)."""
    table = run(gear_pair().replace("t_end: 0.6", "t_end: 5"), formulation=formulation)
    alpha = TORQUE / (J1 + R_GEAR ** 2 * J2)
    t = table["t"]
    assert R_GEAR * alpha * t[-1] ** 2 / 2 < -6 * math.pi  # three turns of disk 2
    for joint, rate in (("p1", alpha), ("p2", R_GEAR * alpha)):
        gap = np.angle(np.exp(1j * (table[f"{joint}.angle"] - rate * t ** 2 / 2)))
        # integrated at rtol 1e-11 over 5 s: to the integrator's tolerance
        np.testing.assert_allclose(gap, 0.0, rtol=0, atol=1e-6, err_msg=joint)
    _close(table["mesh.torque"][0], J2 * R_GEAR * alpha, "gear torque")
    # the multipliers along the run: to the DAE's tolerance
    np.testing.assert_allclose(table["mesh.torque"], J2 * R_GEAR * alpha, rtol=1e-7, atol=0)
    assert table["constraint_violation"].max() <= 1e-8


def test_a_gear_of_a_ratio_no_fraction_gives_is_linear_in_its_angles():
    """Ratio -sqrt(2): no fraction of denominator up to 1000, so its row is the linear sum of
    the angles, which holds inside half a turn: the closed form there."""
    ratio = -math.sqrt(2)
    table = run(gear_pair(f"{{name: mesh, type: gear, joint_i: p1, joint_j: p2, "
                          f"ratio: {ratio!r}}}"))
    alpha = TORQUE / (J1 + ratio ** 2 * J2)
    _close(table["d1.alphaz"][0], alpha, "alpha_1")
    _close(table["mesh.torque"][0], J2 * ratio * alpha, "gear torque")


def geared_four_bar() -> str:
    """models/four_bar_released.yaml with a flywheel on a ground pivot geared to the rocker
    (ratio -2) and a slider tied to the rocker and the flywheel by a coupler of three
    coordinates (slide + 0.1 rocker + 0.02 flywheel = 0): a loop with couplings of a tree
    joint and a slider's, 1 DOF."""
    text = (MODELS / "four_bar_released.yaml").read_text()
    bodies = """
  - {name: flywheel, mass: 2.0, inertia: [0.02, 0.02, 0.04], position: [3, 0, 0]}
  - {name: block, mass: 0.5, inertia: [0.001, 0.001, 0.001], position: [3, 1, 0]}
joints:"""
    joints = """
  - {name: fly_pivot, type: revolute, body_i: ground, body_j: flywheel, at: [3, 0, 0],
     axis: [0, 0, 1]}
  - {name: slide, type: translational, body_i: ground, body_j: block, at: [3, 1, 0],
     axis: [1, 0, 0]}
  - {name: mesh, type: gear, joint_i: rocker_pivot, joint_j: fly_pivot, ratio: -2}
  - {name: tie, type: coupler, joints: [slide, rocker_pivot, fly_pivot],
     coefficients: [1, 0.1, 0.02]}

outputs:"""
    return text.replace("\njoints:", bodies, 1).replace("\n\noutputs:", joints, 1)


def test_joint_and_rp_agree_on_a_geared_loop():
    """The geared four-bar in joint coordinates (the loop's cut joint and both couplings as
    closure rows) and in rp: the same motion and the couplings' reactions, and the couplings
    hold in the joint run's joint values."""
    functions = casmech.compile(casmech.loads(geared_four_bar()))
    tables, metadata = {}, {}
    for formulation in ("joint", "rp"):
        result = casmech.analyze(functions, "dynamics", formulation=formulation, t_end=1.0,
                                 output_step=0.05, rtol=1e-10, atol=1e-12)
        metadata[formulation] = result.metadata
        tables[formulation] = Table(*casmech.results_table(functions, result))
    joint, rp = tables["joint"], tables["rp"]
    assert metadata["joint"]["formulation"] == "joint" and metadata["rp"]["formulation"] == "rp"
    assert set(metadata["joint"]["cut_joints"]) == {"rocker_pin", "mesh", "tie"}
    assert np.ptp(joint["rocker_pivot.angle"]) > 0.2  # the mechanism moves
    for column in ("rocker_pivot.angle", "fly_pivot.angle", "slide.displacement",
                   "crank_pivot.angle", "block.x", "coupler.y"):
        # two formulations integrated at rtol 1e-10 over 1 s
        np.testing.assert_allclose(joint[column], rp[column], rtol=0, atol=1e-7, err_msg=column)
    for column in ("mesh.torque", "tie.force", "rocker_pivot.fx"):
        scale = np.max(np.abs(rp[column]))
        assert scale > 1e-3, column  # the couplings carry load
        # multipliers of two DAEs at rtol 1e-10: their algebraic tolerance
        np.testing.assert_allclose(joint[column], rp[column], rtol=0, atol=1e-6 * scale,
                                   err_msg=column)
    # the couplings in the joint run's own joint values (assembly and DAE tolerance)
    np.testing.assert_allclose(joint["fly_pivot.angle"], -2 * joint["rocker_pivot.angle"],
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(joint["slide.displacement"], -0.1 * joint["rocker_pivot.angle"]
                               - 0.02 * joint["fly_pivot.angle"], rtol=0, atol=1e-9)


@pytest.mark.parametrize("formulation", ["rp", "joint"])
def test_a_redundant_gear_shares_the_torque_as_the_minimum_norm_multipliers(formulation):
    """Two equal gears between the same joints: one row is masked at t0 and the reactions are
    the minimum-norm ones, half the closed-form torque J2 r alpha on each, in both
    formulations."""
    twice = gear_pair().replace(
        "  - {name: mesh,", f"  - {{name: again, type: gear, joint_i: p1, joint_j: p2, "
        f"ratio: {R_GEAR}}}\n  - {{name: mesh,")
    functions = casmech.compile(casmech.loads(twice))
    result = casmech.analyze(functions, "dynamics", formulation=formulation)
    assert result.metadata["formulation"] == formulation
    table = Table(*casmech.results_table(functions, result))
    alpha = TORQUE / (J1 + R_GEAR ** 2 * J2)
    _close(table["d1.alphaz"][0], alpha, "alpha_1")
    for name in ("mesh", "again"):
        # along the run: the DAE's algebraic tolerance
        np.testing.assert_allclose(table[f"{name}.torque"], J2 * R_GEAR * alpha / 2,
                                   rtol=1e-8, atol=0, err_msg=name)
