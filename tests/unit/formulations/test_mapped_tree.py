"""The mapped joint system of a large tree (formulations/mapped_tree.py, mapped_rows.py,
mapped_system.py) against the unrolled SX one (formulations/joint_system.build, a second
implementation of the same recursions: articulated.py's per-joint Python over SX, with gravity
as body wrenches instead of the ground's acceleration): the ODE, the results rows and the
relative poses at random states of several tree shapes, and `supported` refusing what the
kernels do not cover."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.elements.joint_types import MOTIONS
from casmech.formulations import mapped_system, mapped_tree
from casmech.formulations.joint_system import build, layout
from casmech.formulations.tree import spanning_tree
from tests.conftest import MODELS

# every tree-joint type on oblique axes in two branches from ground, body_i the child of the
# universal and of the second cylindrical joint, a fixed joint and a floating block (a free
# tree joint); gravity oblique: no motion is planar
ZOO = """
casmech: 1
name: mapped_zoo
gravity: [0, -9.81, -2.0]
bodies:
  - {name: b1, mass: 1.0, inertia: [0.02, 0.03, 0.025, 0.001, 0.0, 0.002], position: [0.3, 0, 0]}
  - {name: b2, mass: 0.8, inertia: [0.01, 0.02, 0.015], position: [0.6, 0.1, 0]}
  - {name: b3, mass: 0.6, inertia: [0.01, 0.012, 0.008], position: [0.9, 0.1, 0.1]}
  - {name: b4, mass: 0.5, inertia: [0.006, 0.007, 0.005], position: [1.2, 0.0, 0.1]}
  - {name: b5, mass: 0.4, inertia: [0.004, 0.005, 0.006], position: [1.5, 0.0, 0.2]}
  - {name: b6, mass: 0.3, inertia: [0.003, 0.002, 0.004], position: [1.7, 0.1, 0.2]}
  - {name: b7, mass: 0.3, inertia: [0.002, 0.003, 0.0025], position: [1.9, 0.1, 0.3]}
  - {name: c1, mass: 1.2, inertia: [0.03, 0.02, 0.04], position: [-0.3, 0.2, 0]}
  - {name: c2, mass: 0.7, inertia: [0.01, 0.015, 0.012], position: [-0.6, 0.3, 0.1]}
  - {name: block, mass: 2.0, inertia: [0.05, 0.06, 0.07], position: [0, -1.0, 0.5]}
joints:
  - {name: r1, type: revolute, body_i: ground, body_j: b1, at: [0, 0, 0], axis: [0.2, 0.1, 1]}
  - {name: p2, type: translational, body_i: b1, body_j: b2, at: [0.5, 0.05, 0],
     axis: [1, 0.3, 0.2]}
  - {name: cy3, type: cylindrical, body_i: b2, body_j: b3, at: [0.75, 0.1, 0.05],
     axis: [0.1, 1, 0.3]}
  - {name: u4, type: universal, body_i: b4, body_j: b3, at: [1.05, 0.05, 0.1],
     axis_i: [0, 1, 0], axis_j: [0, 0, 1]}
  - {name: pl5, type: planar, body_i: b4, body_j: b5, at: [1.35, 0.0, 0.15], axis: [0.3, 0.2, 1]}
  - {name: f6, type: fixed, body_i: b5, body_j: b6, at: [1.6, 0.05, 0.2]}
  - {name: s7, type: spherical, body_i: b6, body_j: b7, at: [1.8, 0.1, 0.25]}
  - {name: rc1, type: revolute, body_i: ground, body_j: c1, at: [0, 0.1, 0], axis: [1, 0, 0.2]}
  - {name: cyc2, type: cylindrical, body_i: c2, body_j: c1, at: [-0.45, 0.25, 0.05],
     axis: [0.2, 1, 0]}
analysis: {type: dynamics, t_end: 1.0, output_step: 0.01}
"""


def spherical_chain(n: int, axial: float = 1e-4) -> str:
    """benchmarks/systems.py's chain: n bars of 1 m and 1 kg on spherical joints, by default
    its small axial inertia (the case the blockwise elimination is for)."""
    bodies = "\n".join(f"  - {{name: bar{k}, mass: 1.0, inertia: [{axial!r}, 0.0833, 0.0833], "
                       f"position: [{k - 0.5}, 0, 0]}}" for k in range(1, n + 1))
    joints = "\n".join(f"  - {{name: j{k}, type: spherical, body_i: "
                       f"{'ground' if k == 1 else f'bar{k - 1}'}, body_j: bar{k}, "
                       f"at: [{k - 1.0}, 0, 0]}}" for k in range(1, n + 1))
    return (f"casmech: 1\nname: chain{n}\ngravity: [0, 0, -9.81]\nbodies:\n{bodies}\n"
            f"joints:\n{joints}\nanalysis: {{type: dynamics, t_end: 1.0, output_step: 0.1}}\n")


# a branched tree of revolute and sliding joints: a trunk with three branches, one of them
# forked again, written children before parents in places
BRANCHED = """
casmech: 1
name: branched
gravity: [0.5, -9.81, 0.3]
bodies:
  - {name: trunk, mass: 2.0, inertia: [0.1, 0.2, 0.15], position: [0, 0.5, 0]}
  - {name: left, mass: 1.0, inertia: [0.02, 0.03, 0.025], position: [-0.5, 1.0, 0.1]}
  - {name: right, mass: 1.1, inertia: [0.03, 0.02, 0.02], position: [0.5, 1.0, -0.1]}
  - {name: up, mass: 0.7, inertia: [0.01, 0.01, 0.012], position: [0, 1.5, 0]}
  - {name: fork_a, mass: 0.4, inertia: [0.004, 0.005, 0.003], position: [-1.0, 1.2, 0.2]}
  - {name: fork_b, mass: 0.5, inertia: [0.005, 0.004, 0.006], position: [-0.9, 1.4, -0.2]}
joints:
  - {name: base, type: revolute, body_i: ground, body_j: trunk, at: [0, 0, 0], axis: [0, 1, 0.1]}
  - {name: fa, type: revolute, body_i: fork_a, body_j: left, at: [-0.8, 1.1, 0.15],
     axis: [0.3, 0, 1]}
  - {name: l, type: revolute, body_i: trunk, body_j: left, at: [-0.2, 0.9, 0], axis: [0, 0, 1]}
  - {name: r, type: translational, body_i: trunk, body_j: right, at: [0.2, 0.9, 0],
     axis: [1, 0.2, 0]}
  - {name: u, type: revolute, body_i: trunk, body_j: up, at: [0, 1.0, 0], axis: [1, 0, 0.3]}
  - {name: fb, type: translational, body_i: left, body_j: fork_b, at: [-0.8, 1.3, -0.1],
     axis: [0, 1, 1]}
analysis: {type: dynamics, t_end: 1.0, output_step: 0.01}
"""

# no degree of freedom: an empty state, the weld's reactions the whole results row
WELDED = """
casmech: 1
name: welded
gravity: [0.3, 0, -9.81]
bodies:
  - {name: a, mass: 1.0, inertia: [0.1, 0.2, 0.15], position: [0.5, 0, 0]}
  - {name: b, mass: 2.0, inertia: [0.1, 0.15, 0.2], position: [1.5, 0.2, 0]}
joints:
  - {name: w1, type: fixed, body_i: ground, body_j: a, at: [0, 0, 0]}
  - {name: w2, type: fixed, body_i: a, body_j: b, at: [1, 0, 0]}
analysis: {type: dynamics, t_end: 1.0, output_step: 0.1}
"""

RNG = np.random.default_rng(36)


def random_state(system) -> np.ndarray:
    x = RNG.uniform(-0.9, 0.9, system.layout.n_x)
    for joint, index in zip(system.tree.joints, system.layout.theta, strict=True):
        for start in MOTIONS[joint.type].quaternions:
            block = list(index[start:start + 4])
            x[block] /= np.linalg.norm(x[block])
    return x


def _values(outputs) -> list[np.ndarray]:
    outputs = outputs if isinstance(outputs, (list, tuple)) else [outputs]
    return [np.array(v.full()) for v in outputs]


# the relative bound of each model: roundoff (1e-12 of the values' scale); the benchmark's
# chain, whose axial inertia is 1/833 of the transverse one, amplifies roundoff by up to that
# ratio along the chain (3.4e-12 seen over 20 states): 1e-11
@pytest.mark.parametrize("text, bound", [(ZOO, 1e-12), (spherical_chain(7, 0.01), 1e-12),
                                         (BRANCHED, 1e-12), (spherical_chain(7), 1e-11),
                                         (WELDED, 1e-12)],
                         ids=["every_joint_type", "spherical_chain", "branched",
                              "benchmark_chain", "welded"])
def test_mapped_system_equals_the_unrolled_one(text, bound):
    ir = casmech.compile(casmech.loads(text)).ir
    tree = spanning_tree(ir)
    assert mapped_tree.supported(ir, tree) is None
    unrolled, mapped = build(ir, tree), mapped_system.build(ir, tree)
    assert mapped.dynamics.is_a("MXFunction") and mapped.layout == unrolled.layout
    for t in (0.0, 0.41):
        x = random_state(unrolled)
        signs = RNG.choice([-1.0, 1.0], ir.n_bodies)
        pairs = [(unrolled.dynamics(t, x), mapped.dynamics(t, x)),
                 (unrolled.motion(t, x, [], signs), mapped.motion(t, x, [], signs))]
        q, q_dot = (np.array(v.full()).ravel() for v in unrolled.motion(t, x, [], signs)[:2])
        pairs.append((unrolled.relative_states(q, q_dot), mapped.relative_states(q, q_dot)))
        for expected, got in pairs:
            for a, b in zip(_values(expected), _values(got), strict=True):
                # the same recursion in another association of the same products (and
                # gravity as the ground's acceleration): `bound` of the values' scale
                np.testing.assert_allclose(b, a, rtol=0, atol=bound * np.abs(a).max(initial=1.0))


def test_the_chain_state_is_consistent_with_its_tree():
    """Independent of the unrolled build: the mapped rows' r-p state satisfies every joint
    (the bundle's phi and its velocity rows), and its multipliers solve the r-p equations."""
    functions = casmech.compile(casmech.loads(spherical_chain(5)))
    ir, tree = functions.ir, spanning_tree(functions.ir)
    system = mapped_system.build(ir, tree)
    x = random_state(system)
    q, q_dot, q_ddot, lam = (np.array(v.full()).ravel()
                             for v in system.motion(0.2, x, [], np.ones(ir.n_bodies)))
    np.testing.assert_allclose(functions.vector("phi", 0.2, q), 0, rtol=0, atol=1e-12)
    velocity = functions.matrix("phi_q", 0.2, q) @ q_dot - functions.vector("nu", 0.2, q)
    np.testing.assert_allclose(velocity, 0, rtol=0, atol=1e-11)  # roundoff
    from casmech.runtime import assembly

    expected, multipliers = assembly.solve_dynamic_accelerations(functions, 0.2, q, q_dot)
    # the r-p saddle point in double precision: 1e-8 of the scale (test_joint_system's bound)
    np.testing.assert_allclose(q_ddot, expected, rtol=0, atol=1e-8 * np.abs(expected).max())
    m = functions.n_joint_rows
    np.testing.assert_allclose(lam[:m], multipliers[:m], rtol=0,
                               atol=1e-8 * np.abs(multipliers[:m]).max())


@pytest.mark.parametrize("model, reason", [
    ("four_bar.yaml", "loop closures"),
    ("pendulum.yaml", None),
    ("table_driver.yaml", "prescribes"),
    ("double_pendulum.yaml", None),
    ("bushing_mount.yaml", "force elements"),
])
def test_supported_names_what_the_kernels_do_not_cover(model, reason):
    ir = casmech.compile(casmech.load(MODELS / model)).ir
    found = mapped_tree.supported(ir, spanning_tree(ir))
    if reason is None:
        assert found is None
    else:
        assert reason in found
    assert mapped_system.chosen(ir, spanning_tree(ir), 0) == (reason is None)
    assert not mapped_system.chosen(ir, spanning_tree(ir), ir.n_bodies)


def test_a_parametric_tree_is_not_supported():
    from casmech.model import parametric

    functions = casmech.compile(casmech.loads(spherical_chain(2)))
    ir = parametric.split(functions.ir).ir
    assert "parametric" in mapped_tree.supported(ir, spanning_tree(ir))


def test_kernels_depend_on_the_joint_type_alone():
    """Chains of different lengths and body data call the same kernel Functions: the
    single-joint ones, and the block ones where the chain has BLOCK joints in a row."""
    singles = {mapped_tree.kernel_name("spherical", step) for step in mapped_tree.PASSES}
    blocks = {mapped_tree.block_name("spherical", step, mapped_tree.BLOCK)
              for step in mapped_tree.PASSES}
    for n, expected in ((2, singles), (mapped_tree.BLOCK + 1, singles | blocks)):
        ir = casmech.compile(casmech.loads(spherical_chain(n))).ir
        ode = mapped_tree.tree_ode(ir, spanning_tree(ir))
        assert {f.name() for f in ode.find_functions()} == expected
        # at most three calls per body and their outputs, not the unrolled recursion's
        # instructions
        assert ode.n_instructions() < 20 * n + 20


def branched_chain(n: int, branch: int) -> str:
    """spherical_chain(n) with one more bar on a spherical joint at bar `branch`."""
    extra = (f"  - {{name: side, mass: 0.5, inertia: [0.01, 0.02, 0.02], "
             f"position: [{branch - 0.5}, 0.5, 0]}}\n")
    text = spherical_chain(n, 0.01).replace("joints:\n", extra + "joints:\n")
    return text.replace("analysis:", f"  - {{name: js, type: spherical, body_i: bar{branch}, "
                        f"body_j: side, at: [{branch - 0.5}, 0, 0]}}\nanalysis:")


def test_blocks_cover_runs_of_a_chain_and_equal_the_single_joint_kernels():
    """A block covers BLOCK joints in a row of a chain, none across a body with a second
    child; the passes over blocks give the single-joint passes' values."""
    ir = casmech.compile(casmech.loads(branched_chain(11, 3))).ir
    tree = spanning_tree(ir)
    runs = mapped_tree.segments(tree)
    for first, count in runs:
        chain = tree.joints[first:first + count]
        assert count in (1, mapped_tree.BLOCK)
        assert all(b.parent == a.child for a, b in zip(chain[:-1], chain[1:], strict=True))
        # every body inside a block has the block's next joint as its only child
        assert all(sum(j.parent == a.child for j in tree.joints) == 1 for a in chain[:-1])
    assert sorted(k for first, count in runs for k in range(first, first + count)) == \
        list(range(len(tree.joints)))
    assert any(count > 1 for _, count in runs)  # (some joints run in blocks)
    n_x = layout(tree).n_x
    x = ca.MX.sym("x", n_x)
    blocked, single = (ca.Function("f", [x], [p.ode, *p.v, *p.a]) for p in (
        mapped_tree.Passes(ir, tree, x), mapped_tree.Passes(ir, tree, x, size=1)))
    state = RNG.uniform(-0.9, 0.9, n_x)
    for a, b in zip(_values(single(state)), _values(blocked(state)), strict=True):
        # the same kernels' arithmetic, inlined into the blocks: equal to roundoff
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-14 * np.abs(a).max(initial=1.0))
