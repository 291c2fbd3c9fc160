"""Joint-space dynamics of a tree: the mass matrix, the bias forces, forward and inverse
dynamics and their derivatives, as CasADi Functions of the tree's joint coordinates and as
NumPy calls, under the names a Pinocchio user knows (docs/api.md#joint-space-dynamics).

Coordinates: the spanning tree's (formulations/tree.py) free coordinates q (nq) and velocities
v (nv), per tree joint in tree order, as formulations/joint_system.py's layout orders the
state x = [q; v] of the joint ODE (an angle per revolute joint, 0 at the file's pose; the
Euler parameters of a spherical joint with its relative angular velocity in the child's joint
frame as velocities, so nq > nv there; coordinates a driver prescribes are functions of t and
not in q). Then

    M(t, q) a + b(t, q, v) = tau

- inverse dynamics tau(t, q, v, a): the recursive Newton-Euler algorithm of
  formulations/rnea.py (O(n));
- M: the mass matrix, d tau / d a (what the composite-rigid-body algorithm computes);
- b: the bias forces, tau at a = 0: C(q, v) v minus the generalized force of every applied
  force of the model (gravity, springs, dampers, force elements, effort motors, stops); for a
  model whose only applied force is gravity this is Pinocchio's nonlinear effects C v + g;
- forward dynamics a(t, q, v, tau): the articulated-body algorithm of
  formulations/articulated.py with tau as the joints' generalized forces along their free
  velocities (O(n));
- the inverse dynamics' derivatives by CasADi's AD of the Newton-Euler graph; the forward
  dynamics' from them (rnea.forward_derivatives, which also serves any other Jacobian of the
  accelerations, e.g. the joint ODE's in t and x at a known a), with respect to the
  coordinates q (Pinocchio's are with respect to the tangent space; they agree where
  nq = nv).

Mechanisms with loops have no joint space of their own (their cut joints' constraints bind
the coordinates): build refuses them, naming the cut joints.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import field

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.elements.joint_types import MOTIONS
from casmech.errors import UsageError
from casmech.formulations import articulated, joint_forces, rnea
from casmech.formulations.articulated import NUMERIC
from casmech.formulations.joint_constants import DATA, Constants
from casmech.formulations.joint_system import labels, layout
from casmech.formulations.tree import Tree, spanning_tree
from casmech.model.ir import GROUND_INDEX, ModelIR

# function name -> (input names, output names); Pinocchio's name in docs/api.md
SIGNATURES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "mass_matrix": (("t", "q"), ("M",)),
    "bias_forces": (("t", "q", "v"), ("b",)),
    "forward_dynamics": (("t", "q", "v", "tau"), ("a",)),
    "inverse_dynamics": (("t", "q", "v", "a"), ("tau",)),
    "forward_dynamics_derivatives": (("t", "q", "v", "tau"), ("da_dq", "da_dv", "da_dtau")),
    "inverse_dynamics_derivatives": (("t", "q", "v", "a"), ("dtau_dq", "dtau_dv", "dtau_da")),
    "forward_kinematics": (("t", "q", "v"), ("q_bodies", "q_dot_bodies")),
}
# the outputs that are vectors: the NumPy calls give them as 1-D arrays, the others as 2-D
VECTORS = frozenset({"b", "a", "tau", "q_bodies", "q_dot_bodies"})


def functions(ir: ModelIR, tree: Tree, joint_local: bool = True,
              constants: Constants = NUMERIC) -> dict[str, ca.Function]:
    """The SIGNATURES' functions of a tree (module docstring), SX; the elements local to one
    tree joint as generalized forces on its coordinates (formulations/joint_forces.py; not
    `joint_local`: as body wrenches). Over model.parametric.split's IR, with `constants` over
    its symbols, each function takes last the input "d" of the tree's constants
    (joint_constants.Constants.inputs: the compiled space, backends.joint_space_library)."""
    lay = layout(tree)
    nq, nv = lay.n_theta, lay.n_x - lay.n_theta
    t, q, v = ca.SX.sym("t"), ca.SX.sym("q", nq), ca.SX.sym("v", nv)
    tau, acceleration = ca.SX.sym("tau", nv), ca.SX.sym("a", nv)
    x = ca.vertcat(q, v)
    reference = {j.child: j.child_frame for j in tree.joints}
    joints = [articulated.Joint(j, t, {c: x[k] for c, k in zip(fq, kq, strict=True)},
                                {c: x[k] for c, k in zip(fv, kv, strict=True)},
                                reference.get(j.parent), constants)
              for j, kq, kv, fq, fv in zip(tree.joints, lay.theta, lay.u, lay.free_theta,
                                           lay.free_u, strict=True)]
    kin = articulated.kinematics(joints, ir.n_bodies, constants)
    forces = joint_forces.TreeForces(ir, tree, joints, kin, t, joint_local)
    torques = [local + tau[[k - nq for k in slots]] if slots else ca.SX(0, 1)
               for local, slots in zip(forces.torques, lay.u, strict=True)]
    dynamics = articulated.articulated_body(ir, joints, kin, forces.wrenches, torques)
    forward = ca.vertcat(*dynamics.u_dot) if nv else ca.SX(0, 1)
    u_dot = [acceleration[[k - nq for k in slots]] if slots else ca.SX(0, 1) for slots in lay.u]
    inverse = forces.inverse_dynamics(u_dot) if nv else ca.SX(0, 1)
    mass = ca.jacobian(inverse, acceleration)
    bias = ca.substitute(inverse, acceleration, ca.DM.zeros(nv))
    bodies = articulated.state(kin, ir.n_bodies)
    data = [constants.inputs] if constants.symbolic else []

    def _function(name: str, inputs: list, outputs: list) -> ca.Function:
        input_names, output_names = SIGNATURES[name]
        return ca.Function(name, inputs + data, outputs,
                           list(input_names) + [DATA] * bool(data), list(output_names))

    return {
        "mass_matrix": _function("mass_matrix", [t, q], [mass]),
        "bias_forces": _function("bias_forces", [t, q, v], [bias]),
        "forward_dynamics": _function("forward_dynamics", [t, q, v, tau], [forward]),
        "inverse_dynamics": _function("inverse_dynamics", [t, q, v, acceleration], [inverse]),
        "forward_dynamics_derivatives": _function(
            "forward_dynamics_derivatives", [t, q, v, tau],
            rnea.forward_derivatives(inverse, acceleration, forward, [q, v])),
        "inverse_dynamics_derivatives": _function(
            "inverse_dynamics_derivatives", [t, q, v, acceleration],
            [ca.jacobian(inverse, wrt) for wrt in (q, v, acceleration)]),
        "forward_kinematics": _function("forward_kinematics", [t, q, v], list(bodies)),
    }


@record
class JointSpace:
    """A tree's joint-space dynamics (module docstring): CasADi Functions by name
    (`functions`, SIGNATURES) and NumPy calls, Pinocchio's argument order with t last."""

    functions: Mapping[str, ca.Function]
    coordinates: tuple[str, ...]  # names of q
    velocities: tuple[str, ...]  # names of v and of tau, a
    joints: tuple[str, ...]  # the tree joints, in tree order ('' for a floating body's)
    neutral: np.ndarray  # q at the file's pose: zeros, unit quaternions [1, 0, 0, 0]
    # name -> the NumPy call of that function (arrays in; out fresh arrays, VECTORS 1-D and
    # matrices 2-D: the array of a function of one output, else a tuple of them), given by
    # whoever makes the space (casmech.joint_space: through buffers); None: casadi's own call
    calls: Mapping[str, Callable] | None = field(default=None, compare=False)

    def __post_init__(self):
        if self.calls is None:  # (the methods call self.calls[name] with no test)
            object.__setattr__(self, "calls", _CasadiCalls(self.functions))

    @property
    def nq(self) -> int:
        return len(self.coordinates)

    @property
    def nv(self) -> int:
        return len(self.velocities)

    def __getitem__(self, name: str) -> ca.Function:
        return self.functions[name]

    # (each method calls its function's call itself, with no helper between: a Python frame
    # is a visible part of a compiled function's call)
    def mass_matrix(self, q, t: float = 0.0) -> np.ndarray:
        """M(q) (nv x nv); Pinocchio's crba."""
        return self.calls["mass_matrix"](t, q)

    def bias_forces(self, q, v, t: float = 0.0) -> np.ndarray:
        """b(t, q, v) (nv); Pinocchio's nonLinearEffects where gravity is the only force."""
        return self.calls["bias_forces"](t, q, v)

    def forward_dynamics(self, q, v, tau, t: float = 0.0) -> np.ndarray:
        """The accelerations a (nv) under joint forces tau; Pinocchio's aba."""
        return self.calls["forward_dynamics"](t, q, v, tau)

    def inverse_dynamics(self, q, v, a, t: float = 0.0) -> np.ndarray:
        """The joint forces tau (nv) that give accelerations a; Pinocchio's rnea."""
        return self.calls["inverse_dynamics"](t, q, v, a)

    def forward_dynamics_derivatives(self, q, v, tau, t: float = 0.0) -> tuple:
        """(da/dq, da/dv, da/dtau = M^-1); Pinocchio's computeABADerivatives."""
        return self.calls["forward_dynamics_derivatives"](t, q, v, tau)

    def inverse_dynamics_derivatives(self, q, v, a, t: float = 0.0) -> tuple:
        """(dtau/dq, dtau/dv, dtau/da = M); Pinocchio's computeRNEADerivatives."""
        return self.calls["inverse_dynamics_derivatives"](t, q, v, a)

    def forward_kinematics(self, q, v=None, t: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """The bodies' r-p coordinates and their rates (casmech's q and q_dot: positions
        r_1..r_nb, then Euler parameters p_1..p_nb) at the joint state."""
        v = np.zeros(self.nv) if v is None else v
        return self.calls["forward_kinematics"](t, q, v)

    def __repr__(self) -> str:
        return (f"JointSpace(nq={self.nq}, nv={self.nv}, joints={list(self.joints)}, "
                f"functions={list(self.functions)})")


class _CasadiCalls(Mapping):
    """name -> CasADi's own call of functions[name] (numbers, lists and arrays in; out as
    JointSpace.calls gives them)."""

    def __init__(self, functions: Mapping[str, ca.Function]):
        self._functions = functions

    def __getitem__(self, name: str) -> Callable[..., tuple]:
        function = self._functions[name]

        def call(*args):
            outputs = function(*(np.asarray(a, float) for a in args))
            outputs = outputs if isinstance(outputs, tuple) else (outputs,)
            arrays = tuple(np.array(out.full()).ravel() if output in VECTORS else
                           np.array(out.full())
                           for output, out in zip(function.name_out(), outputs, strict=True))
            return arrays[0] if len(arrays) == 1 else arrays

        return call

    def __iter__(self) -> Iterator[str]:
        return iter(self._functions)

    def __len__(self) -> int:
        return len(self._functions)


def joint_space(ir: ModelIR, calls: Callable[[Mapping[str, ca.Function]], Mapping] | None = None,
                made: Callable[[], tuple[Mapping[str, ca.Function], Mapping]] | None = None
                ) -> JointSpace:
    """The joint space of a lowered model whose joints form a tree (module docstring); `calls`
    makes its NumPy calls of its functions (None: casadi's own call); `made`, where given,
    makes (the functions, their NumPy calls) instead (a compiled space:
    backends.joint_space_library), once the model is known to be a tree."""
    tree = spanning_tree(ir)
    if tree.cut:
        names = ", ".join(f"'{j.name}'" + (f" ({j.source})" if j.source else "")
                          for j in tree.cut)
        raise UsageError(f"{ir.name}: a joint space needs a tree of joints; these joints close "
                         f"loops or have no joint coordinates: {names}; its equations are "
                         "casmech.compile's r-p functions (mass_matrix, phi_q, ...)")
    coordinates, velocities = labels(tree, tuple(b.name for b in ir.bodies))  # x's names
    lay = layout(tree)
    neutral = np.zeros(lay.n_theta)
    for joint, slots, free in zip(tree.joints, lay.theta, lay.free_theta, strict=True):
        for start in MOTIONS[joint.type].quaternions:
            if start in free:  # a quaternion's coordinates are free together
                neutral[slots[free.index(start)]] = 1.0
    names = tuple(j.name or ("ground" if j.child == GROUND_INDEX else ir.bodies[j.child].name)
                  for j in tree.joints)
    if made is not None:
        space_functions, space_calls = made()
    else:
        space_functions = functions(ir, tree)
        space_calls = None if calls is None else calls(space_functions)
    return JointSpace(space_functions, coordinates, velocities, names, neutral, space_calls)
