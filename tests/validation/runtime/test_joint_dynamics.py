"""Dynamics in joint coordinates (runtime/joint_dynamics.py) against the r-p DAE and closed
forms."""

import numpy as np
import pytest

import casmech
from casmech.elements.joint_types import MOTIONS
from casmech.errors import AnalysisError, ModelError
from casmech.formulations.articulated import local_motion
from casmech.formulations.joint_start import constant_inverse
from casmech.formulations.tree import spanning_tree
from tests.conftest import MODELS, ROOT, Table, count_calls
from tests.validation.runtime.test_dynamics import FREE_BODY, G, W

ZOO = ROOT / "tests" / "helpers" / "joint_zoo.yaml"
VALIDATION = MODELS / "validation"
TREES = [ZOO, *(MODELS / f"{name}.yaml" for name in (
    "double_pendulum", "triple_pendulum", "flyball_governor", "cart_pole",
    "bushing_mount", "user_force_pendulum", "chain_repeat", "quadruped_legs")),
    *(VALIDATION / f"{name}.yaml" for name in (
        "iftomm_a01_pendulum", "revolute_case01", "spherical_case01", "universal_case01",
        "cylindrical_case01", "prismatic_case01", "rotspring_case01", "transpring_case01"))]
POSITION = ("x", "y", "z", "e0", "e1", "e2", "e3")


def tables(functions, formulations, **kwargs):
    return {name: Table(*casmech.results_table(functions, casmech.analyze(
        functions, formulation=name, **kwargs))) for name in formulations}


@pytest.mark.parametrize("path", TREES, ids=lambda p: p.stem)
def test_same_motion_as_the_rp_dae(path):
    """Every tree model: positions, velocities and reactions of the joint formulation equal
    the r-p DAE's over 0.5 s, both at rtol 1e-10."""
    functions = casmech.compile(casmech.load(path))
    out = tables(functions, ("joint", "rp"), t_end=0.5, output_step=0.05, rtol=1e-10,
                 atol=1e-12)
    joint, rp = out["joint"], out["rp"]
    for name in joint.names[1:]:
        kind = name.rsplit(".", 1)[-1]
        scale = max(1.0, np.max(np.abs(rp[name])))
        # two integrators at rtol 1e-10 on the same motion: global errors of ~1e-9 of the
        # scale in positions (measured <= 4e-9 m); accelerations and reactions, algebraic in
        # the state, carry it amplified by the stiffness of the model (measured <= 4e-7)
        tolerance = 1e-7 if kind in POSITION else 2e-6
        np.testing.assert_allclose(joint[name], rp[name], rtol=0, atol=tolerance * scale,
                                   err_msg=name)
    assert np.max(joint["constraint_violation"]) <= 1e-12  # the tree keeps joints exactly


def test_free_flight_is_the_closed_form():
    """A free body is a `free` tree joint: parabola and steady spin, exactly."""
    functions = casmech.compile(casmech.loads(FREE_BODY))
    table = tables(functions, ("joint",))["joint"]
    t = table["t"]
    start, velocity = np.array([0, 0, 1.0]), np.array([1.0, -0.5, 4.0])
    position = start[:, None] + np.outer(velocity, t) + 0.5 * np.outer(G, t**2)
    for k, axis in enumerate("xyz"):
        # rtol 1e-10 over 2 s; the translation is exactly quadratic, so Adams is near exact
        np.testing.assert_allclose(table[f"box.{axis}"], position[k], rtol=0, atol=1e-8)
        np.testing.assert_allclose(table[f"box.a{axis}"], G[k], rtol=0, atol=1e-10)
    np.testing.assert_allclose(table["box.e0"], np.cos(W * t / 2), rtol=0, atol=1e-8)
    np.testing.assert_allclose(table["box.e3"], np.sin(W * t / 2), rtol=0, atol=1e-8)


def test_energy_is_conserved_and_error_shrinks_with_rtol():
    """The double pendulum is conservative: energy constant to the tolerance, and 100x
    tighter rtol gives at least 10x smaller position error against rtol 1e-12."""
    functions = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    runs = {rtol: tables(functions, ("joint",), t_end=2.0, rtol=rtol, atol=rtol / 100)["joint"]
            for rtol in (1e-6, 1e-8, 1e-12)}
    energy = runs[1e-12]["energy"]
    # kinetic + potential at rtol 1e-12: constant to 1e-9 of its scale (measured ~1e-11)
    np.testing.assert_allclose(energy, energy[0], rtol=0, atol=1e-9 * np.max(np.abs(energy)))
    error = {rtol: np.max(np.abs(runs[rtol]["rod2.x"] - runs[1e-12]["rod2.x"]))
             for rtol in (1e-6, 1e-8)}
    assert error[1e-8] <= error[1e-6] / 10


def test_heavy_top_error_shrinks_with_rtol():
    """Steady precession: the CM stays at its tilt and turns about z at the closed-form rate
    Omega (models/heavy_top.yaml), pulled by the joint with m (a - g); the error falls with
    the tolerance. (The heavy top is checked against the closed form, not the r-p DAE: at 100
    rad/s of spin that one was 4.6e-6 N off this reaction at rtol 1e-12, 4.2e-8 at 1e-10.)"""
    model = casmech.load(MODELS / "heavy_top.yaml")
    p = model.parameters
    functions = casmech.compile(model)
    errors = []
    for rtol in (1e-6, 1e-8, 1e-10):
        table = tables(functions, ("joint",), t_end=1.0, rtol=rtol, atol=rtol / 100)["joint"]
        angle = p["Omega"] * table["t"]
        radius = p["l"] * np.sin(p["theta0"])
        expected = np.stack([radius * np.cos(angle), radius * np.sin(angle)])
        errors.append(np.max(np.abs(np.stack([table["top.x"], table["top.y"]]) - expected)))
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] <= 100 * 1e-10 * p["l"]  # within ~100 rtol of the motion's scale
    force = -p["m"] * p["Omega"] ** 2 * expected[0]
    # reaction at rtol 1e-10: measured 8.3e-8 N off on a force of 0.21 N
    np.testing.assert_allclose(table["tip.fx"], force, rtol=0, atol=1e-6)


def test_auto_picks_joint_for_trees():
    tree = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    assert casmech.analyze(tree, formulation="auto", t_end=0.05).metadata["formulation"] == "joint"


def test_metadata_names_the_tree():
    functions = casmech.compile(casmech.load(ZOO))
    meta = casmech.analyze(functions, formulation="joint", t_end=0.02).metadata
    assert meta["tree"][:3] == ["r1", "rc1", "p2"]
    assert meta["tree"][-1] == "free 'block'"
    assert meta["cut_joints"] == []


LOOPS = [ROOT / "benchmarks" / "models" / "four_bar.yaml", MODELS / "bricard.yaml",
         VALIDATION / "distance_case01.yaml", VALIDATION / "revspherical_case01.yaml"]


@pytest.mark.parametrize("path", LOOPS, ids=lambda p: p.stem)
def test_loops_move_as_in_the_rp_dae(path):
    """Cut joints close loops (the four-bar's pin, Bricard's redundant hinge, a distance and a
    revolute-spherical link): positions and reactions as the r-p DAE's, constraints kept."""
    functions = casmech.compile(casmech.load(path))
    assert not spanning_tree(functions.ir).is_tree
    out = tables(functions, ("joint", "rp"), t_end=0.5, output_step=0.05, rtol=1e-10,
                 atol=1e-12)
    joint, rp = out["joint"], out["rp"]
    for name in joint.names[1:]:
        scale = max(1.0, np.max(np.abs(rp[name])))
        # as for the trees; the reactions of Bricard's redundant row are the minimum-norm
        # ones in both (measured <= 1.3e-6 of the scale in its accelerations)
        tolerance = 1e-7 if name.rsplit(".", 1)[-1] in POSITION else 5e-6
        np.testing.assert_allclose(joint[name], rp[name], rtol=0, atol=tolerance * scale,
                                   err_msg=name)
    # GGL holds Phi = 0 at every step; unit rows, IDAS's Newton tolerance on them
    assert np.max(joint["constraint_violation"]) <= 1e-9


BLOWING_UP = """
casmech: 1
name: blowing_up
bodies:
  - {name: bar, mass: 1.0, inertia: [0.1, 0.1, 0.01], position: [0, 1, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [1, 0, 0]}
forces:
  - {name: push, type: torque, body: bar, value: ["1 / (0.305 - t)**3", 0, 0]}
analysis: {type: dynamics, t_end: 1, output_step: 0.01}
"""


def test_a_failure_keeps_the_rows_before_it():
    """A torque that diverges at t = 0.305: the integrator gives up there; exit-3 error naming
    the output interval, the rows before it kept."""
    functions = casmech.compile(casmech.loads(BLOWING_UP))
    with pytest.raises(AnalysisError, match="integrator failed between") as failure:
        casmech.analyze(functions, formulation="joint")
    rows = failure.value.partial.times
    assert 0.25 <= rows[-1] <= 0.305  # every interval before the divergence was kept
    assert f"t = {rows[-1]:.6g}" in str(failure.value)  # it names where it stopped


STIFF_ARM = """
casmech: 1
name: stiff_arm
bodies:
  - {name: arm, mass: 1.0, inertia: [0.01, 0.1, 0.1], position: [0.5, 0, 0]}
  - {name: tip, mass: 0.5, inertia: [0.001, 0.001, 0.001], position: [1.0, 0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: arm, at: [0, 0, 0], axis: [0, 1, 0]}
forces:
  - {name: mount, type: bushing, body_i: arm, body_j: tip, at: [1.0, 0, 0],
     stiffness: [1e7, 1e7, 1e7], damping: [3000, 3000, 3000],
     rotational_stiffness: [1e5, 1e5, 1e5], rotational_damping: [30, 30, 30]}
analysis: {type: dynamics, t_end: 0.5, output_step: 0.01, rtol: 1.0e-8, atol: 1.0e-10}
"""


def test_method_auto_takes_bdf_for_a_stiff_tree_and_both_agree():
    """A tip on a stiff bushing (fastest mode ~3e4 1/s against a 0.01 s grid) runs by BDF
    under auto, a chain (interpreted) by Adams; Adams and BDF give the same motion."""
    stiff = casmech.compile(casmech.loads(STIFF_ARM))
    runs = {m: casmech.analyze(stiff, method=m) for m in ("auto", "adams", "bdf")}
    assert runs["auto"].metadata["method"] == "bdf"
    assert runs["bdf"].metadata["steps"] < runs["adams"].metadata["steps"] / 5
    chain = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    assert casmech.analyze(chain, t_end=0.1).metadata["method"] == "adams"
    adams, bdf = (Table(*casmech.results_table(stiff, runs[m])) for m in ("adams", "bdf"))
    for name in ("tip.x", "tip.z", "arm.e2"):
        # two methods at rtol 1e-8: BDF's global error on this stiff tip scatters from 2e-7
        # to 3e-6 m with its step sequence (against a run at rtol 1e-12), Adams' is ~4e-9
        np.testing.assert_allclose(adams[name], bdf[name], rtol=0, atol=5e-6, err_msg=name)


def test_method_auto_does_not_examine_a_tree_without_force_elements(monkeypatch):
    """Gravity, inertia and drivers only: an explicit method (Adams, interpreted) without the
    ODE's Jacobian (the stiffness test is for force elements); the stiff arm above is
    examined."""
    chain = casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))
    casmech.analyze(chain, t_end=0.02)  # the joint system built outside the count
    calls = count_calls(monkeypatch)
    assert casmech.analyze(chain, t_end=0.02).metadata["method"] == "adams"
    assert not any("jac" in name or "fwd" in name for name in calls), calls


@pytest.mark.parametrize("kind", [k for k in MOTIONS if MOTIONS[k].n_v])
def test_joint_velocities_by_the_constant_inverse_equal_least_squares(kind):
    """Where a joint type's S_J is constant, S_J^+ twist is lstsq(S_J(theta), twist) at random
    coordinates; universal, planar and free have a varying S_J and get none."""
    motion, rng = MOTIONS[kind], np.random.default_rng(7)
    inverse = constant_inverse(kind)
    assert (inverse is None) == (kind in ("universal", "planar", "free"))
    if inverse is None:
        return
    for _ in range(3):
        theta = rng.normal(size=motion.n_q)
        for start in motion.quaternions:
            theta[start:start + 4] /= np.linalg.norm(theta[start:start + 4])
        subspace = np.array(local_motion(kind)(theta, np.zeros(motion.n_v))[2].full())
        twist = subspace @ rng.normal(size=motion.n_v) + 1e-3 * rng.normal(size=6)
        # both are the least-squares solution of a well-conditioned 6 x n_v system
        np.testing.assert_allclose(inverse @ twist,
                                   np.linalg.lstsq(subspace, twist, rcond=None)[0],
                                   rtol=0, atol=1e-13)


def test_method_adams_on_a_dae_is_a_located_error():
    text = STIFF_ARM.replace("atol: 1.0e-10}", "atol: 1.0e-10, formulation: rp,\n  method: adams}")
    with pytest.raises(ModelError) as error:
        casmech.loads(text, file="arm.yaml")
    line = next(k for k, row in enumerate(text.splitlines(), 1) if "method: adams" in row)
    assert f"arm.yaml:{line}:" in str(error.value) and "error[E409]" in str(error.value)


def test_runs_reusing_kept_integrators_repeat_exactly():
    """A later run over the same grid with the same options reuses the kept CVODES instance:
    it must give the first run's rows bit for bit, also after runs with other options and
    grids in between; the kept instances stay bounded."""
    from casmech.runtime.workspace import KINDS, Workspace

    functions = casmech.compile(casmech.load(ZOO))
    workspace = Workspace(functions)

    def run(rtol, t_end=0.3):
        return casmech.analyze(functions, "dynamics", formulation="joint", t_end=t_end,
                               rtol=rtol, atol=rtol * 1e-2, method="adams",
                               workspace=workspace)

    first = run(1e-8)
    for k in range(KINDS["cvodes"] + 2):
        run(1e-6, t_end=0.1 + 0.01 * k)
    again, other = run(1e-8), run(1e-6)
    np.testing.assert_array_equal(again.q, first.q)  # the same computation, repeated
    assert np.max(np.abs(other.q - first.q)) > 0  # the options are part of what is kept
    assert len(workspace.store("cvodes")) == KINDS["cvodes"]


def test_a_large_tree_builds_quickly_unless_flags_are_chosen(monkeypatch):
    """The tree's ODE above compile.quick_build_instructions compiles at -O0 (the rows too),
    below at the default flags with the results rows at joint_library.ROWS_FLAGS, both with
    the machine's instruction set (joint_library.machine); $CASMECH_CFLAGS always wins."""
    from casmech.backends import build, joint_library
    from casmech.runtime import joint_dynamics

    system = joint_dynamics.joint_system(
        casmech.compile(casmech.load(MODELS / "double_pendulum.yaml")))
    monkeypatch.delenv(build.FLAGS_ENVIRONMENT, raising=False)
    size = system.dynamics.n_instructions()
    names = ("joint_ode", "joint_motion", "joint_motion_part0")
    quick = joint_dynamics._toolchain(system, size - 1, names)
    assert quick.flags == ("-O0",) and quick.flags_of("joint_motion") == ("-O0",)
    default = joint_dynamics._toolchain(system, size, names)
    machine = joint_library.machine()  # the machine's instruction set, on both
    assert default.flags == build.DEFAULT_FLAGS + machine
    assert default.flags_of("joint_ode") == build.DEFAULT_FLAGS + machine
    assert default.flags_of("joint_motion") == default.flags_of("joint_motion_part0") \
        == joint_library.ROWS_FLAGS + machine != build.DEFAULT_FLAGS + machine
    monkeypatch.setenv(build.FLAGS_ENVIRONMENT, "-O2 -march=native")
    chosen = joint_dynamics._toolchain(system, size - 1, names)
    assert chosen.flags == chosen.flags_of("joint_motion") == ("-O2", "-march=native")


def test_a_second_run_from_the_same_start_reuses_its_initial_state(monkeypatch):
    """The assembled initial state, its joint coordinates, multipliers and quaternion signs are
    a function of the bundle and t0: a second run computes none of them (no assembly call)
    and gives the first run's rows bit for bit; another t0 assembles again."""
    from casmech.runtime import assembly

    functions = casmech.compile(casmech.load(MODELS / "bricard.yaml"))
    first = casmech.analyze(functions, formulation="joint", t_end=0.1)
    assembled = []
    original = assembly.initial_state
    monkeypatch.setattr(assembly, "initial_state",
                        lambda f, t0, *args: assembled.append(t0) or original(f, t0, *args))
    again = casmech.analyze(functions, formulation="joint", t_end=0.1)
    assert assembled == []
    for name in ("q", "q_dot", "q_ddot", "lam"):
        np.testing.assert_array_equal(getattr(again, name), getattr(first, name))
    from casmech.runtime.joint_dynamics import run_joint_dynamics
    run_joint_dynamics(functions, 0.2, 0.05, 1e-8, 1e-10, t0=0.1)
    assert assembled == [0.1]


def test_a_repeated_loop_run_creates_no_integrator_and_repeats_exactly(monkeypatch):
    """The loops' IDAS instance depends on the run's start (its first step, initial
    derivative and tolerances): a run from the same start over the same grid reuses it, with
    the same rows bit for bit; another grid creates one."""
    from tests.integration.runtime.test_dynamics_reuse import counted

    functions = casmech.compile(casmech.load(ROOT / "benchmarks" / "models" / "four_bar.yaml"))
    first = casmech.analyze(functions, formulation="joint", method="bdf", t_end=0.3)
    created = counted(monkeypatch)
    again = casmech.analyze(functions, formulation="joint", method="bdf", t_end=0.3)
    assert created == []
    for name in ("q", "q_dot", "q_ddot", "lam"):
        np.testing.assert_array_equal(getattr(again, name), getattr(first, name))
    casmech.analyze(functions, formulation="joint", method="bdf", t_end=0.2)
    assert created == ["idas"]
