"""The joint formulation as CasADi Functions: the ODE of a tree, the DAE of a tree with loop
closures, and the results row's state.

State x = [theta; u]: the coordinates and velocities of the tree joints that no driver
prescribes (formulations/articulated.py). A tree is the ODE x' = (theta_dot, ABA). Cut joints keep
their constraint rows Phi_c(t, q(theta)) (formulations/tree.py; a coupling of joint coordinates
is always cut, its row over the bodies of the joints it couples: rows_of). Their multipliers act
on every body the rows read as the r-omega constraint wrenches -[Phi_r, Pi_bar]^T lam, and the
DAE is the stabilized index-2 form of Gear, Gupta and Leimkuhler (as formulations/dae.py's for
r-p):

    theta' = theta_dot(theta, u) + Phi_c_theta^T S mu,   u' = ABA(t, theta, u; lam)
    0 = S Phi_c(t, theta),   0 = S d/dt Phi_c (t, theta, u),   z = [lam, mu]

with S = diag(s(theta)) scaling each row to unit velocity-Jacobian norm (lam in force units)
and the rows masked by p = w (w_k = 1 turns row k into lam_k = 0 and mu_k = 0: rows that
depend on the others at t0). The stabilizing term takes S as a factor, not differentiated
(d S/d theta multiplies Phi_c, zero on the constraint manifold): any matrix B with
Phi_c_theta B nonsingular gives the same projection, and this one costs fewer of the
residual's instructions than (S Phi_c)_theta (docs/decisions/loop-dae-stabilization.md).

Over a parametric IR (model.parametric.split, `build(ir, tree, data=symbols)`) every function
takes a trailing input "d": the model data extended by the constants of the tree
(formulations/joint_constants.py), which JointSystem.data computes from the model data once per
parameter value.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache, cached_property

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.core.records import record
from casmech.elements.joint_types import MOTIONS, state_names
from casmech.elements.primitives import PRIMITIVES, Frame
from casmech.formulations import articulated
from casmech.formulations.articulated import Joint
from casmech.formulations.joint_constants import DATA, Constants
from casmech.formulations.tree import Tree
from casmech.model.ir import GROUND_INDEX, JointIR, ModelIR
from casmech.numerics import lazy_jacobian

# (the build's kernels, equations.body, equations.row_kernels, formulations.joint_forces, rnea
# and tree_steps, are imported by the functions that build: a warm run loads the system
# compiled)

# a cut row whose velocity Jacobian in joint coordinates is shorter than this (its units:
# the row's per unit joint velocity, m or 1) is one the tree cannot violate: roundoff of 0
ROW_NORM_FLOOR = 1e-9
# the largest tree ODE (states) whose Jacobian build's RNEA identity gives: its symbolic
# derivative grows with the square of the tree, past which forward sweeps build faster
IDENTITY_STATES = 200


@record
class Layout:
    """Which coordinates and velocities are states: per tree joint, the indices into x of its
    free coordinates and velocities, and which of its own they are."""

    theta: tuple[tuple[int, ...], ...]
    u: tuple[tuple[int, ...], ...]
    free_theta: tuple[tuple[int, ...], ...]
    free_u: tuple[tuple[int, ...], ...]
    n_theta: int
    n_x: int


def layout(tree: Tree) -> Layout:
    free_theta = [tuple(c for c in range(MOTIONS[j.type].n_q) if c not in j.prescribed)
                  for j in tree.joints]
    free_u = [tuple(c for c in range(MOTIONS[j.type].n_v) if c not in j.prescribed)
              for j in tree.joints]
    n, slots = 0, []
    for free in (*free_theta, *free_u):
        slots.append(tuple(range(n, n + len(free))))
        n += len(free)
    k = len(tree.joints)
    return Layout(tuple(slots[:k]), tuple(slots[k:]), tuple(free_theta), tuple(free_u),
                  sum(map(len, free_theta)), n)


def labels(tree: Tree, body_names: tuple[str, ...]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(names of the free coordinates, of the free velocities), in x's order:
    `<joint>.<name>`, the names of elements.joint_types.state_names (a joint's results
    columns where they are its states), a floating body's `<body>.free.<name>`."""
    lay = layout(tree)
    coordinates, velocities = [], []
    for joint, free_q, free_v in zip(tree.joints, lay.free_theta, lay.free_u, strict=True):
        q_names, v_names = state_names(joint.type)
        owner = joint.name or f"{body_names[joint.child]}.free"
        coordinates += [f"{owner}.{q_names[k]}" for k in free_q]
        velocities += [f"{owner}.{v_names[k]}" for k in free_v]
    return tuple(coordinates), tuple(velocities)


@record
class JointSystem:
    tree: Tree
    layout: Layout
    cut_rows: tuple[int, ...]  # rows of Phi the cut joints own (the DAE's algebraic rows)
    dynamics: ca.Function  # tree: (t, x) -> ode; loops: (t, x, z, p) -> (ode, alg)
    # (t, x, z, signs) -> (q, q_dot, q_ddot, lam), its common subexpressions merged (ca.cse)
    motion: ca.Function
    # loops: (t, x) -> (d acceleration residual / dz, that residual at z = 0), where the
    # residual d^2/dt^2 Phi_c (unit rows) is affine in z (multipliers enter as forces)
    acceleration_system: ca.Function
    velocity_jacobian: ca.Function  # loops: (t, x) -> d/du of d/dt Phi_c (unit rows)
    relative_states: ca.Function  # (q, q_dot) -> each tree joint's relative pose (_relative)
    # a parametric build's d -> its functions' trailing input (None: a numeric build)
    data: ca.Function | None = None
    # dynamics' Jacobian (jacobian()'s signature) given by a compiled library, else built
    given_jacobian: ca.Function | None = None
    # a numeric tree's: () -> its ODE's Jacobian by the RNEA identity (_Builder.ode_jacobian),
    # built on the first call; jacobian()'s signature (t, x, ode) -> (d ode/dt, d ode/dx)
    identity_jacobian: Callable[[], ca.Function] | None = None
    # loops: (t, x, w, signs) -> (q, q_dot, q_ddot, lam), the rows with the loop multipliers
    # solved at (t, x) (runtime.joint_rows.solved_motion), compiled with the motion
    solved_motion: ca.Function | None = None

    @property
    def n_cut(self) -> int:
        return len(self.cut_rows)

    @cached_property
    def problem(self) -> dict:
        """casadi.integrator's problem (MX). Its Jacobian: a compiled library's when given; a
        tree's by the RNEA identity when the build made one (numeric IR, up to build's
        identity_states), else by lazy_jacobian's forward sweeps (cheap to build for
        a large ODE); the loops' DAE's symbolic, built once (IDAS evaluates it at every
        linear-solver setup, where the forward sweeps cost far more per evaluation:
        docs/decisions/loop-dae-stabilization.md)."""
        if self.given_jacobian is not None or self.identity_jacobian is not None:
            return lazy_jacobian.problem(self.dynamics, jacobian=self.jacobian)
        if self.n_cut:  # compiled: the library holds it (runtime.joint_dynamics)
            return lazy_jacobian.problem(self.dynamics, jacobian=self.dynamics.jacobian())
        return lazy_jacobian.problem(self.dynamics)

    @cached_property
    def jacobian(self) -> ca.Function:
        """The given Jacobian, else the RNEA identity's (a numeric build's), else
        lazy_jacobian.jacobian of `dynamics`, built once."""
        if self.given_jacobian is not None:
            return self.given_jacobian
        if self.identity_jacobian is not None:
            return self.identity_jacobian()
        return lazy_jacobian.jacobian(self.dynamics)

    @cached_property
    def functional_problem(self) -> dict:
        """The same for CVODES's functional iteration, which never evaluates a Jacobian."""
        return lazy_jacobian.problem(self.dynamics, exact=False)


def _relative(tree_joints, q, q_dot, constants: Constants) -> list:
    """(rotations [3 x 3n], gaps [3 x n], twists [6 x n]) of every tree joint at (q, q_dot): the
    child frame F_c's rotation and origin relative to the parent frame F_p (in F_p), and its
    twist relative to F_p (angular, then the origin's velocity, in F_c), JointSystem's
    relative_states (runtime.joint_dynamics takes each joint's coordinates and velocities
    from them). Every body is the child of one tree joint."""
    from casmech.formulations.tree_steps import relative_step

    n_bodies = len(tree_joints)
    poses = [ca.vertsplit(v, [*range(0, 3 * n_bodies, 3), *range(3 * n_bodies, 7 * n_bodies + 1,
                                                                   4)]) for v in (q, q_dot)]

    def state(k: int) -> list:
        """(r, p, r_dot, p_dot) of body k (ground: at rest at the origin)."""
        if k == GROUND_INDEX:
            return [ca.DM.zeros(3), ca.DM([1, 0, 0, 0]), ca.DM.zeros(3), ca.DM.zeros(4)]
        return [poses[0][k], poses[0][n_bodies + k], poses[1][k], poses[1][n_bodies + k]]

    steps = [relative_step(*state(joint.parent), *state(joint.child),
                           *(constants(v) for v in (*joint.parent_frame, *joint.child_frame)))
             for joint in tree_joints]
    return [ca.horzcat(*parts) for parts in zip(*steps, strict=True)]


def joint_bodies(ir: ModelIR, joint: JointIR) -> tuple[int, ...]:
    """The bodies a joint's rows read, body_i and body_j first, then a coupling's others
    (PrimitiveIR.others: the bodies of the joints it couples), ground included."""
    prims = ir.primitives[joint.rows.start:joint.rows.stop]
    return tuple(dict.fromkeys((joint.body_i, joint.body_j,
                                *(b for prim in prims for b in prim.bodies))))


def rows_of(ir: ModelIR, joint: JointIR, t, r_i, p_i, r_j, p_j, *others, data=None) -> list:
    """(phi, B_1, ..., B_n): a joint's constraint rows at the poses of the bodies it reads
    (joint_bodies: (r_i, p_i), (r_j, p_j), then `others` as r, p pairs; SX; ground's ignored)
    and their r-omega Jacobians at each of those bodies, [Phi_r, Pi_bar] (global translation,
    body-frame rotation; zero for ground); through one Function per structure of the joint's
    rows (their kinds, which bodies each reads, which are ground, the vectors' shapes) that
    takes the rows' vectors and driver values as inputs (rows_template); `data` the model
    data of a parametric IR, whose vectors are SX of it."""
    from casmech.equations.row_kernels import driver_value

    template, vectors, prims = rows_structure(ir, joint, data)
    if data is not None:
        stacked = ca.vertcat(ca.SX(0, 1), *(ca.vec(ca.SX(v)) for v in vectors))
    else:
        stacked = ca.SX(np.concatenate([np.zeros(0), *(np.ravel(v) for v in vectors)]))
    drivers = ca.vertcat(*(driver_value(prim, t) for prim in prims))
    poses = (r_i, p_i, r_j, p_j, *others)
    return template.call([v if isinstance(v, ca.SX) else ca.SX(v)
                          for v in (*poses, stacked, drivers)])


def rows_structure(ir: ModelIR, joint: JointIR, data=None) -> tuple[ca.Function, list, list]:
    """(rows_template of a joint's rows, their vectors in its order, the rows' primitives);
    `data` as for rows_of."""
    prims = ir.primitives[joint.rows.start:joint.rows.stop]
    bodies = joint_bodies(ir, joint)
    vectors = [prim.vectors[k] for prim in prims for k in PRIMITIVES[prim.kind][1]]
    shapes = tuple(ca.SX(v).shape if data is not None else np.shape(v) for v in vectors)
    reads = tuple(tuple(bodies.index(b) for b in prim.bodies) for prim in prims)
    return rows_template(tuple(p.kind for p in prims), tuple(b == GROUND_INDEX for b in bodies),
                         shapes, reads), vectors, prims


@cache
def rows_template(kinds: tuple[str, ...], grounds: tuple[bool, ...],
                  shapes: tuple[tuple[int, ...], ...],
                  reads: tuple[tuple[int, ...], ...]) -> ca.Function:
    """(r_1, p_1, ..., r_n, p_n, the rows' vectors stacked, their driver values) -> (phi,
    B_1, ..., B_n) of rows of these kinds (rows_of), each row reading the bodies at its
    `reads` positions, built from the rows' primitives so that the cost stays per joint."""
    from casmech.equations import body

    sides = [(ca.SX.sym(f"r_{k}", 3), ca.SX.sym(f"p_{k}", 4)) for k in range(len(grounds))]
    frames = [Frame(ca.DM.zeros(3), ca.DM.eye(3)) if ground else Frame(r, euler.rotation(p))
              for ground, (r, p) in zip(grounds, sides, strict=True)]
    sizes = [int(np.prod(shape)) for shape in shapes]
    stacked = ca.SX.sym("v", sum(sizes))
    parts = ca.vertsplit(stacked, list(np.cumsum([0, *sizes]))) if sizes else []
    vectors = [ca.reshape(part, *(shape if len(shape) == 2 else (size, 1)))
               for part, shape, size in zip(parts, shapes, sizes, strict=True)]
    drivers = ca.SX.sym("f", len(kinds))
    rows, given = [], iter(vectors)
    for k, (kind, read) in enumerate(zip(kinds, reads, strict=True)):
        function, keys = PRIMITIVES[kind]
        rows.append(function(*(frames[b] for b in read), {key: next(given) for key in keys},
                             drivers[k]))
    phi = ca.vertcat(*rows)
    blocks = [ca.horzcat(ca.jacobian(phi, r), body.pi_bar(ca.jacobian(phi, p), p))
              for r, p in sides]
    return ca.Function("joint_rows", [*(v for side in sides for v in side), stacked, drivers],
                       [phi, *blocks])


class _Builder:
    """The SX of one model's tree; see build."""

    def __init__(self, ir: ModelIR, tree: Tree, constants: Constants,
                 joint_local: bool = True):
        from casmech.formulations import joint_forces

        self.ir, self.tree, self.layout = ir, tree, layout(tree)
        self.constants = constants
        self.joint_rows: dict[str, list] = {}  # joint name -> rows_of at the tree's state
        lay = self.layout
        self.t, self.x = ca.SX.sym("t"), ca.SX.sym("x", lay.n_x)
        self.cut_rows = tuple(r for j in tree.cut for r in j.rows)
        m = len(self.cut_rows)
        self.z, self.w = ca.SX.sym("z", 2 * m), ca.SX.sym("w", m)
        reference = {j.child: j.child_frame for j in tree.joints}
        self.joints = [
            Joint(j, self.t, {c: self.x[k] for c, k in zip(ft, th, strict=True)},
                  {c: self.x[k] for c, k in zip(fu, us, strict=True)},
                  reference.get(j.parent), constants)
            for j, th, us, ft, fu in zip(tree.joints, lay.theta, lay.u, lay.free_theta,
                                         lay.free_u, strict=True)]
        self.kin = articulated.kinematics(self.joints, ir.n_bodies, constants)
        self.forces = joint_forces.TreeForces(ir, tree, self.joints, self.kin, self.t,
                                              joint_local)
        self.theta_dot = ca.vertcat(*[j.theta_dot[list(free)] if free else ca.SX(0, 1)
                                      for j, free in zip(self.joints, lay.free_theta,
                                                         strict=True)])

    def rows(self, joint: JointIR) -> tuple:
        """(phi, B_i, B_j) of a joint's rows at the tree's state."""
        def pose(body: int):
            if body == GROUND_INDEX:
                return ca.DM.zeros(3), ca.DM([1, 0, 0, 0])
            return self.kin.r[body], self.kin.p[body]
        if joint.name not in self.joint_rows:
            poses = [v for k in joint_bodies(self.ir, joint) for v in pose(k)]
            self.joint_rows[joint.name] = rows_of(self.ir, joint, self.t, *poses,
                                                  data=self.constants.data)
        return self.joint_rows[joint.name]

    def loop_closure(self):
        """(Phi_c, d/dt Phi_c, the unit-row scale, lam, mu) of the cut rows."""
        m = len(self.cut_rows)
        theta = self.x[:self.layout.n_theta]
        phi = ca.vertcat(*[self.rows(joint)[0] for joint in self.tree.cut])
        rate = ca.jacobian(phi, theta) @ self.theta_dot + ca.jacobian(phi, self.t)
        u = self.x[self.layout.n_theta:]
        norm = ca.sqrt(ca.sum2(ca.jacobian(rate, u) ** 2))
        # a row the tree's motions cannot violate (a planar loop's out-of-plane rows) has no
        # velocity Jacobian: scale 0, so the rank test at t0 masks it
        scale = ca.if_else(norm > ROW_NORM_FLOOR, 1 / norm, 0)
        return phi, rate, scale, self.z[:m], self.z[m:]

    def cut_wrenches(self, lam) -> list:
        """Body wrenches (n_bar, A^T F) of the cut rows' multipliers lam (true units): each
        body takes -B^T lam of the rows acting on it."""
        wrenches = [ca.SX.zeros(6, 1) for _ in range(self.ir.n_bodies)]
        start = 0
        for joint in self.tree.cut:
            _, *blocks = self.rows(joint)
            lam_j = lam[start:start + len(joint.rows)]
            start += len(joint.rows)
            for k, block in zip(joint_bodies(self.ir, joint), blocks, strict=True):
                if k == GROUND_INDEX:
                    continue
                generalized = -block.T @ lam_j  # global force, body-frame torque
                wrenches[k] += ca.vertcat(generalized[3:6],
                                          self.kin.rotation[k].T @ generalized[0:3])
        return wrenches

    def dynamics(self, lam, tau=None):
        """The articulated-body accelerations under the applied forces, the cut rows'
        multipliers lam and generalized forces tau along the free velocities (x's u part,
        in its order; none: zero)."""
        cut = self.cut_wrenches(lam)
        external = [a + c for a, c in zip(self.forces.wrenches, cut, strict=True)]
        torques = self.forces.torques  # the joint-local elements' (joint_forces)
        if tau is not None:
            start = self.layout.n_theta
            torques = [local + tau[[k - start for k in slots]] if slots else ca.SX(0, 1)
                       for local, slots in zip(torques, self.layout.u, strict=True)]
        return articulated.articulated_body(self.ir, self.joints, self.kin, external, torques)

    def ode_jacobian(self) -> ca.Function:
        """A tree's ODE's Jacobian by (t, x) from its inverse dynamics (Carpentier and Mansard
        2018, rnea.forward_derivatives): d u'/d(t, x) = -M^-1 dRNEA/d(t, x) at u' = the ODE
        value, an input, so no articulated-body sweep is re-run; theta' by CasADi's AD.
        (t, x, ode) -> (d ode/dt, d ode/dx): jacobian()'s signature (a numeric IR's)."""
        from casmech.formulations import rnea

        lay = self.layout
        n_u = lay.n_x - lay.n_theta
        ode, u_dot = ca.SX.sym("ode", lay.n_x), ca.SX.sym("u_dot", n_u)
        accelerations = [u_dot[[k - lay.n_theta for k in slots]] if slots else ca.SX(0, 1)
                         for slots in lay.u]
        tau = self.forces.inverse_dynamics(accelerations)
        by_t, by_x, _ = rnea.forward_derivatives(tau, u_dot, ode[lay.n_theta:],
                                                 [self.t, self.x])
        outputs = [ca.vertcat(ca.jacobian(self.theta_dot, self.t), by_t),
                   ca.vertcat(ca.jacobian(self.theta_dot, self.x), by_x)]
        return ca.Function("jac_joint_ode", [self.t, self.x, ode], outputs, ["t", "x", "ode"],
                           ["jac_ode_t", "jac_ode_x"])

    def multipliers(self, dynamics, lam_cut) -> ca.SX:
        """Every joint row's multiplier: the cut rows' from the DAE, each tree joint's rows
        from its constraint wrench w on the child, -B^T lam = w with B the rows' r-omega
        Jacobian at the child (global force, body-frame torque)."""
        from casmech.formulations.tree_steps import translation_pivots, tree_multipliers

        lam = ca.SX.zeros(len(self.ir.row_info()), 1)
        lam[list(self.cut_rows)] = lam_cut
        wrenches = articulated.joint_wrenches(self.joints, dynamics,
                                              self.forces.local_wrenches())
        for j, w in zip(self.joints, wrenches, strict=True):
            joint = j.joint.joint
            if joint is None:  # a floating body's free joint has no rows
                continue
            _, block_i, block_j = self.rows(joint)
            block = block_i if j.joint.child == joint.body_i else block_j
            lam[list(joint.rows)] = tree_multipliers(block, self.kin.rotation[j.joint.child],
                                                     w, pivots=translation_pivots(block))[0]
        return lam

    def motion(self, dynamics, lam_cut, signs) -> list:
        """(q, q_dot, q_ddot, lam) of the results row: r-p, Euler parameters times signs."""
        from casmech.formulations.tree_steps import body_rates

        nb, kin = self.ir.n_bodies, self.kin
        signed = ca.vertsplit(signs)
        p, p_dot, r_ddot, p_ddot = zip(*[
            body_rates(signed[k], kin.p[k], kin.rotation[k], kin.velocity[k],
                       dynamics.accelerations[k]) for k in range(nb)], strict=True)
        return [ca.vertcat(*kin.r, *p),
                ca.vertcat(*[kin.r_dot(k) for k in range(nb)], *p_dot),
                ca.vertcat(*r_ddot, *p_ddot), self.multipliers(dynamics, lam_cut)]


def forced_ode(ir: ModelIR, tree: Tree, data: ca.SX | None = None) -> ca.Function:
    """A tree's ODE with generalized forces along its free velocities as an input:
    (t, x, tau[, d]) -> ode, tau in the order of x's velocities (optimal control's joint
    efforts: ControlEquations.forced, formulations/joint_control.py)."""
    if tree.cut:
        raise ValueError("forced_ode takes a tree (no cut joints)")
    constants = Constants(data)
    b = _Builder(ir, tree, constants)
    tau = ca.SX.sym("tau", b.layout.n_x - b.layout.n_theta)
    dyn = b.dynamics(ca.SX(0, 1), tau)
    inputs = {"t": b.t, "x": b.x, "tau": tau} | ({} if data is None else
                                                 {DATA: constants.inputs})
    return ca.Function("joint_forced_ode", list(inputs.values()),
                       [ca.vertcat(b.theta_dot, *dyn.u_dot)], list(inputs), ["ode"])


def saddle_terms(ir: ModelIR, tree: Tree, data: ca.SX | None = None) -> ca.Function:
    """(t, x) -> (M, P, F, gamma): the loops' DAE at acceleration level as numerics.kkt's
    saddle system [M P^T; P -diag(w)] [u_dot; lam] = [F; gamma], lam the DAE's unit-row
    multipliers: M the tree's joint-space mass matrix and F its generalized forces less the
    bias (the RNEA's d tau/d u_dot and -tau at u_dot = 0), P = S d/du d/dt Phi_c (the DAE's
    velocity Jacobian) and gamma = -S d/dt Phi_c's rate at u_dot = 0; over a parametric IR
    (data: the symbols of model.parametric.split) (t, x, d) -> the same, d the model data
    itself (the tree's constants computed from it inside)."""
    constants = Constants(data)
    b = _Builder(ir, tree, constants)
    _, rate, scale, _, _ = b.loop_closure()
    lay, t = b.layout, b.t
    theta, u = b.x[:lay.n_theta], b.x[lay.n_theta:]
    a = ca.SX.sym("a", lay.n_x - lay.n_theta)
    u_dot = [a[[k - lay.n_theta for k in slots]] if slots else ca.SX(0, 1) for slots in lay.u]
    tau = b.forces.inverse_dynamics(u_dot)
    jacobian = ca.repmat(scale, 1, a.numel()) * ca.jacobian(rate, u)
    gamma = -scale * (ca.jtimes(rate, theta, b.theta_dot) + ca.jacobian(rate, t))
    outputs = [ca.jacobian(tau, a), jacobian, -ca.substitute(tau, a, ca.DM.zeros(a.shape)), gamma]
    names = ["M", "P", "F", "gamma"]
    if data is None:
        return ca.Function("joint_saddle_terms", [t, b.x], ca.cse(outputs), ["t", "x"], names)
    inner = ca.Function("terms", [t, b.x, constants.inputs], outputs)
    outputs = inner.call([t, b.x, constants.function()(data)])
    return ca.Function("joint_saddle_terms", [t, b.x, data], ca.cse(outputs),
                       ["t", "x", DATA], names)


def build(ir: ModelIR, tree: Tree, data: ca.SX | None = None,
          identity_states: int = IDENTITY_STATES, joint_local: bool = True) -> JointSystem:
    """The joint system of a numeric IR, or (data: the symbols of model.parametric.split)
    of a parametric one, every function with the trailing input "d" (module docstring); a
    numeric tree's of up to identity_states states with its ODE's Jacobian by the RNEA
    identity (JointSystem.identity_jacobian, built when first asked for). A build over
    symbols makes none: its constants are hoisted into the data input as they are met, and the
    data function is fixed with the build (docs/decisions/joint-derivatives.md). Elements local
    to one tree joint act on its coordinates (formulations/joint_forces.py; not `joint_local`:
    as body wrenches, like every other applied force)."""
    constants = Constants(data)
    b = _Builder(ir, tree, constants, joint_local)
    t, x, z, w = b.t, b.x, b.z, b.w
    signs = ca.SX.sym("signs", ir.n_bodies)
    if not b.cut_rows:
        dyn = b.dynamics(ca.SX(0, 1))
        x_dot = ca.vertcat(b.theta_dot, *dyn.u_dot)
        dynamics = ("joint_ode", {"t": t, "x": x}, {"ode": x_dot})
        acceleration = {"matrix": ca.SX(0, 0), "base": ca.SX(0, 1)}
        velocity = ca.SX(0, b.layout.n_x)
        lam_cut = ca.SX(0, 1)
    else:
        phi, rate, scale, lam_unit, mu = b.loop_closure()
        lam_cut = scale * lam_unit
        dyn = b.dynamics(lam_cut)
        x_dot = ca.vertcat(b.theta_dot, *dyn.u_dot)
        theta = x[:b.layout.n_theta]
        ode = x_dot + ca.vertcat(ca.jacobian(phi, theta).T @ (scale * mu),
                                 ca.SX.zeros(b.layout.n_x - b.layout.n_theta, 1))
        alg = ca.vertcat((1 - w) * scale * phi - w * mu, (1 - w) * scale * rate - w * lam_unit)
        dynamics = ("joint_dae", {"t": t, "x": x, "z": z, "p": w}, {"ode": ode, "alg": alg})
        residual = scale * (ca.jacobian(rate, x) @ x_dot + ca.jacobian(rate, t))
        acceleration = {"matrix": ca.jacobian(residual, z),
                        "base": ca.substitute(residual, z, ca.DM.zeros(z.shape))}
        velocity = ca.jacobian(scale * rate, x[b.layout.n_theta:])
    motion = dict(zip(("q", "q_dot", "q_ddot", "lam"), ca.cse(b.motion(dyn, lam_cut, signs)),
                      strict=True))
    poses = {"q": ca.SX.sym("q", 7 * ir.n_bodies), "q_dot": ca.SX.sym("q_dot", 7 * ir.n_bodies)}
    relative = dict(zip(("rotations", "gaps", "twists"),
                        _relative(tree.joints, *poses.values(), constants), strict=True))
    identity = None
    if data is None and not b.cut_rows and b.layout.n_x <= identity_states:
        identity = cache(b.ode_jacobian)
    extra = {} if data is None else {DATA: constants.inputs}

    def function(name: str, inputs: dict, outputs: dict) -> ca.Function:
        inputs = inputs | extra
        return ca.Function(name, list(inputs.values()), list(outputs.values()), list(inputs),
                           list(outputs))

    return JointSystem(
        tree, b.layout, b.cut_rows, function(*dynamics),
        function("joint_motion", {"t": t, "x": x, "z": z, "signs": signs}, motion),
        function("joint_acceleration_system", {"t": t, "x": x}, acceleration),
        function("joint_velocity_jacobian", {"t": t, "x": x}, {"jacobian": velocity}),
        function("joint_relative_states", poses, relative),
        None if data is None else constants.function(),
        identity_jacobian=identity)
