"""The joint system of a large tree as kernels over the tree (formulations/mapped_tree.py for
the ODE, formulations/mapped_rows.py for the results rows): joint_system.build's functions,
with the same names, inputs and outputs, built as MX graphs of per-joint-type kernels instead
of the unrolled SX, so that the build costs a few kernel calls per body and the evaluation
runs in the kernels' compiled code (backends/tree_kernels.py).

runtime.joint_dynamics chooses it (`chosen`) for a tree of more than compile.mapped_bodies
bodies that mapped_tree.supported covers and that the compiled bundle does not compile whole;
every other model takes joint_system.build.
"""

from __future__ import annotations

from collections.abc import Mapping

import casadi as ca

from casmech.formulations import mapped_rows, mapped_tree
from casmech.formulations.joint_system import JointSystem, layout
from casmech.formulations.tree import Tree
from casmech.model.ir import ModelIR


def chosen(ir: ModelIR, tree: Tree, bodies: int) -> bool:
    """Whether a tree of more than `bodies` bodies takes the mapped build."""
    return ir.n_bodies > bodies and mapped_tree.supported(ir, tree) is None


def build(ir: ModelIR, tree: Tree, functions: Mapping[str, ca.Function] | None = None
          ) -> JointSystem:
    """The JointSystem of a supported tree over the kernels `functions` (by name; default the
    SX ones): its ODE, results rows and relative poses; a tree has no algebraic rows. The ODE's
    Jacobian, where an integrator asks for it, comes from forward sweeps through the kernels'
    derivatives (lazy_jacobian)."""
    functions = functions or {}
    lay = layout(tree)
    t, x = ca.MX.sym("t"), ca.MX.sym("x", lay.n_x)
    z, signs = ca.MX.sym("z", 0), ca.MX.sym("signs", ir.n_bodies)
    passes = mapped_tree.Passes(ir, tree, x, functions)
    dynamics = ca.Function("joint_ode", [t, x], [passes.ode], ["t", "x"], ["ode"])
    rows = mapped_rows.Rows(ir, tree, passes, functions).motion(signs)
    motion = ca.Function("joint_motion", [t, x, z, signs], rows, ["t", "x", "z", "signs"],
                         ["q", "q_dot", "q_ddot", "lam"])
    acceleration = ca.Function("joint_acceleration_system", [t, x],
                               [ca.MX(0, 0), ca.MX(0, 1)], ["t", "x"], ["matrix", "base"])
    velocity = ca.Function("joint_velocity_jacobian", [t, x], [ca.MX(0, lay.n_x)],
                           ["t", "x"], ["jacobian"])
    return JointSystem(tree, lay, (), dynamics, motion, acceleration, velocity,
                       mapped_rows.relative_states(tree, ir.n_bodies))
