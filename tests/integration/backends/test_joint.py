"""The joint formulation on a compiled bundle: its tree's ODE and results rows compiled
(runtime.joint_dynamics.compiled_system for the mapped library; for a parametric library
(codegen.parametric) compiled in it over the model data) and equal to the interpreted ones."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.backends import codegen
from casmech.core.options import DynamicsSolver, JointCompile
from casmech.runtime import joint_dynamics
from casmech.runtime.joint_dynamics import joint_system
from casmech.runtime.workspace import Workspace
from tests.conftest import Table

RNG = np.random.default_rng(11)


@pytest.fixture(scope="module")
def compiled(model, toolchain, cache_root):
    """The mapped library of the session's model (it has parameters: by default parametric)."""
    return codegen.compiled(model, toolchain, root=cache_root, parametric_library=False)


def test_a_parametric_bundle_runs_the_tree_from_its_library(model, toolchain, cache_root,
                                                            interpreted):
    bundle = codegen.compiled(model, toolchain, root=cache_root)
    assert bundle.data is not None and codegen.mode_of(bundle) == "compiled"
    fast, slow = joint_system(bundle), joint_system(interpreted)
    assert fast.dynamics is bundle.joint_functions["joint_ode"]
    # the same equations, the model's constants computed from d: roundoff
    _assert_same_tree_functions(fast, slow, interpreted.n_bodies)
    # a tree's Jacobian: forward sweeps of the library's ODE (no identity in the library)
    assert "joint_jacobian" not in bundle.joint_functions and fast.identity_jacobian is None


def _assert_jacobian_is_the_odes(fast, slow) -> None:
    """fast's ODE Jacobian (JointSystem.jacobian) equals CasADi's AD of slow's ODE (the
    articulated-body recursion) at random (t, x)."""
    t_sym, x_sym = ca.SX.sym("t"), ca.SX.sym("x", slow.layout.n_x)
    ode = slow.dynamics(t_sym, x_sym)
    reference = ca.Function("reference", [t_sym, x_sym],
                            [ca.jacobian(ode, t_sym), ca.jacobian(ode, x_sym)])
    for _ in range(3):
        t, x = RNG.uniform(0, 2), RNG.uniform(-0.5, 0.5, slow.layout.n_x)
        for a, b in zip(fast.jacobian(t, x, fast.dynamics(t, x)), reference(t, x), strict=True):
            b = np.array(b)
            # two derivatives of the same dynamics (the compiled ODE's forward sweeps, AD of
            # the interpreted one): roundoff, relative to the largest entry
            np.testing.assert_allclose(np.array(a), b, rtol=0, atol=1e-9 * np.max(np.abs(b)))


def _assert_same_tree_functions(fast, slow, nb: int) -> None:
    """The ODE and the results rows of two joint systems at random (t, x), to 1e-12."""
    for _ in range(3):
        t, x = RNG.uniform(0, 2), RNG.uniform(-0.5, 0.5, slow.layout.n_x)
        np.testing.assert_allclose(np.array(fast.dynamics(t, x)), np.array(slow.dynamics(t, x)),
                                   rtol=1e-12, atol=1e-12)
        for a, b in zip(fast.motion(t, x, [], np.ones(nb)), slow.motion(t, x, [], np.ones(nb)),
                        strict=True):
            np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-12, atol=1e-12)


def test_compiled_tree_functions_equal_the_interpreted(interpreted, compiled):
    fast, slow = joint_system(compiled), joint_system(interpreted)
    assert fast.dynamics.class_name() == "External" and slow.dynamics.is_a("SXFunction")
    # the same SX compiled to C: equal to roundoff
    _assert_same_tree_functions(fast, slow, interpreted.n_bodies)
    # forward sweeps of a compiled ODE (BDF's library, built on first use:
    # backends.joint_library), not the interpreted identity the numeric build offers
    assert fast.jacobian.is_a("MXFunction") and slow.jacobian.is_a("SXFunction")
    _assert_jacobian_is_the_odes(fast, slow)


def test_compiled_run_is_the_interpreted_run(interpreted, compiled):
    runs = [Table(*casmech.results_table(f, casmech.analyze(
        f, "dynamics", formulation="joint", t_end=0.5, rtol=1e-10, atol=1e-12)))
        for f in (interpreted, compiled)]
    for name in runs[0].names[1:]:
        scale = max(1.0, np.max(np.abs(runs[0][name])))
        # the same equations; roundoff may change a step size, within the rtol 1e-10 runs'
        # own error
        np.testing.assert_allclose(runs[1][name], runs[0][name], rtol=0, atol=1e-8 * scale,
                                   err_msg=name)


def test_large_trees_keep_their_results_rows_interpreted(compiled):
    """Above solver.compile.motion_bodies only the ODE is compiled; above ode_bodies nothing
    of the tree (their C builds grow with the tree); each in its own workspace entry."""
    workspace = Workspace(compiled)
    system = joint_system(compiled, DynamicsSolver(compile=JointCompile(motion_bodies=0)),
                          workspace)
    assert system.dynamics.class_name() == "External" and system.motion.is_a("SXFunction")
    system = joint_system(compiled, DynamicsSolver(compile=JointCompile(ode_bodies=0)),
                          workspace)
    assert system.dynamics.is_a("SXFunction") and system.motion.is_a("SXFunction")
    assert len(workspace.store("joint_system")) == 2
    default = joint_system(compiled, workspace=workspace)
    assert default.dynamics.class_name() == "External" and default.motion.class_name() == \
        "External"


def test_a_coupled_mechanism_runs_its_compiled_joint_dae(toolchain, cache_root):
    """The pinion and rack (no parameters: a mapped library) in joint coordinates, the rack's
    coupling a closure row of the compiled joint DAE: the closed-form accelerations and rack
    force, T / (J + m R^2) (tests/validation/runtime/test_couplings.py)."""
    from tests.validation.runtime.test_couplings import J_PINION, M_RACK, R_PINION, RACK, TORQUE

    bundle = codegen.compiled(casmech.loads(RACK), toolchain, root=cache_root)
    assert codegen.mode_of(bundle) == "compiled"
    integrator = DynamicsSolver(loop_rows="integrator")
    assert joint_system(bundle, integrator).solved_motion is None  # only for loop_rows solved
    system = joint_system(bundle)  # loop_rows solved, the default
    assert system.n_cut == 1 and system.dynamics.class_name() == "External"
    # the rows solved at each state (runtime.joint_rows) are compiled with the motion
    assert system.solved_motion.class_name() == "External"
    result = casmech.analyze(bundle, "dynamics", formulation="joint")
    assert result.metadata["formulation"] == "joint"
    table = Table(*casmech.results_table(bundle, result))
    alpha = TORQUE / (J_PINION + M_RACK * R_PINION ** 2)
    # the consistent start solves a linear system: round-off
    np.testing.assert_allclose(table["pinion.alphaz"][0], alpha, rtol=1e-9, atol=0)
    np.testing.assert_allclose(table["teeth.force"][0], M_RACK * R_PINION * alpha, rtol=1e-9,
                               atol=0)
    # every row's multiplier solved at its state by the compiled terms: the same closed form
    np.testing.assert_allclose(table["teeth.force"], M_RACK * R_PINION * alpha, rtol=1e-9,
                               atol=0)



def _refuse_builds(monkeypatch) -> None:
    def refused(*args, **kwargs):
        raise AssertionError("a symbolic joint system was built")

    monkeypatch.setattr(joint_dynamics, "build", refused)


def _assert_same_start_functions(fast, slow) -> None:
    """The functions a run's start and loops evaluate, equal at random states."""
    n = slow.relative_states.size1_in(0)
    for _ in range(2):
        t, x = RNG.uniform(0, 2), RNG.uniform(-0.5, 0.5, slow.layout.n_x)
        q, q_dot = RNG.uniform(-0.5, 0.5, n), RNG.uniform(-0.5, 0.5, n)
        for a, b in ((fast.acceleration_system(t, x), slow.acceleration_system(t, x)),
                     (fast.velocity_jacobian(t, x), slow.velocity_jacobian(t, x)),
                     (fast.relative_states(q, q_dot), slow.relative_states(q, q_dot))):
            for u, v in zip(a if isinstance(a, (list, tuple)) else [a],
                            b if isinstance(b, (list, tuple)) else [b], strict=True):
                # CasADi's serialization of the same graph: the same operations
                np.testing.assert_array_equal(np.array(u), np.array(v))


def test_a_warm_cache_builds_no_joint_system(interpreted, compiled, monkeypatch):
    """The compiled bundle's joint library is keyed by the bundle's own library and the
    settings (runtime.joint_dynamics.keyed_system): once built, a new workspace (a new
    process) takes the tree's ODE, results rows and start functions from the cache without
    building the symbolic system, and they are the interpreted system's; above motion_bodies
    the results rows too are kept beside the library."""
    above = DynamicsSolver(compile=JointCompile(motion_bodies=0))
    for settings in (DynamicsSolver(), above):  # in the cache (maybe already), and BDF's
        assert joint_system(compiled, settings, Workspace(compiled)).jacobian  # Jacobian's
    slow = joint_system(interpreted)
    _refuse_builds(monkeypatch)
    fast = joint_system(compiled, workspace=Workspace(compiled))
    assert fast.dynamics.class_name() == "External"
    _assert_same_tree_functions(fast, slow, interpreted.n_bodies)
    _assert_same_start_functions(fast, slow)
    _assert_jacobian_is_the_odes(fast, slow)
    kept = joint_system(compiled, above, Workspace(compiled))
    assert kept.motion.is_a("SXFunction") and kept.dynamics.class_name() == "External"
    _assert_same_tree_functions(kept, slow, interpreted.n_bodies)


def test_a_warm_cache_builds_no_loop_system(toolchain, cache_root, monkeypatch):
    """The same for the loops' DAE with its solved rows (loop_rows solved): the pinion and
    rack's system from the cache equals the interpreted one."""
    from tests.validation.runtime.test_couplings import RACK

    model = casmech.loads(RACK)
    bundle = codegen.compiled(model, toolchain, root=cache_root)
    interpreted = casmech.compile(model)
    solved = DynamicsSolver(loop_rows="solved")
    joint_system(bundle, solved, Workspace(bundle))
    slow = joint_system(interpreted, solved)
    _refuse_builds(monkeypatch)
    fast = joint_system(bundle, solved, Workspace(bundle))
    assert fast.n_cut == slow.n_cut == 1
    assert fast.solved_motion.class_name() == "External"
    _assert_same_start_functions(fast, slow)
    nb, n_z = interpreted.n_bodies, slow.dynamics.size1_in(2)
    for _ in range(2):
        t, x = RNG.uniform(0, 2), RNG.uniform(-0.5, 0.5, slow.layout.n_x)
        z, p = RNG.uniform(-1, 1, n_z), np.zeros(slow.dynamics.size1_in(3))
        for a, b in zip(fast.dynamics(t, x, z, p), slow.dynamics(t, x, z, p), strict=True):
            # the same SX compiled to C: roundoff
            np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-12, atol=1e-12)
        for a, b in zip(fast.motion(t, x, z, np.ones(nb)), slow.motion(t, x, z, np.ones(nb)),
                        strict=True):
            np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-12, atol=1e-12)


# the four-bar's mapped library builds for a minute or more on loaded cores: slow
@pytest.mark.parametrize("name", [pytest.param("four_bar", marks=pytest.mark.slow), "gear_pair"])
def test_the_compiled_loop_rows_are_the_composed_ones_and_the_rp_multipliers(
        name, toolchain, cache_root):
    """The loop rows solved at each state, compiled as one function in the joint library
    (runtime.joint_rows.solved_motion), against the interpreted terms, LU solve and compiled
    rows one after another and the r-p multipliers at the same state
    (tests/integration/runtime/test_loop_rows.py)."""
    from casmech.formulations.joint_system import saddle_terms
    from tests.conftest import MODELS
    from tests.integration.runtime.test_loop_rows import assert_rows_agree

    bundle = codegen.compiled(casmech.load(MODELS / f"{name}.yaml"), toolchain,
                              root=cache_root, parametric_library=False)
    system = joint_system(bundle, DynamicsSolver(loop_rows="solved"))
    assert system.solved_motion.class_name() == "External"
    assert system.motion.class_name() == "External"
    assert_rows_agree(bundle, system, system.solved_motion, saddle_terms(bundle.ir, system.tree))
