"""The joint formulation's equations for optimal control (formulations.protocol's
ControlEquations, JointCoordinates.controlled): the functions of formulations/joint_system.py
built over the model data's symbols, read with the model data d as their last input.

    ode(t, x, d[, z, mask])    a tree: its ODE (build's joint_ode); loops: the DAE's x'
    forced(t, x, tau, d)       a tree's ODE with the efforts tau (joint_system.forced_ode)
    closure(t, x, d)           loops: the cut rows Phi_c and d/dt Phi_c (unit rows: the DAE's
                               algebraic rows with no row masked and mu = 0)
    multipliers(t, x, d, kept) loops: lam from the kept acceleration-level rows (index 1)
    invariants(x)              |p|^2 - 1 of every quaternion among the coordinates
    state, independent, signs  the start from body coordinates (formulations/joint_start.py)
    body(t, x, z, signs, d)    the results row's r-p state and every row's multiplier
"""

from __future__ import annotations

from functools import cached_property

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.elements.joint_types import MOTIONS
from casmech.equations.checks import independent_rows
from casmech.errors import UsageError
from casmech.formulations.joint_start import ASSEMBLY, continuing_signs, from_relative
from casmech.formulations.joint_system import JointSystem, forced_ode
from casmech.formulations.protocol import ControlEquations
from casmech.model.ir import ModelIR


@record(eq=False)
class JointControl(ControlEquations):
    """ControlEquations of the joint formulation: `joints` built over `symbols` (the model
    data's) from `ir`, the parametric IR written in them."""

    joints: JointSystem
    ir: ModelIR
    symbols: ca.SX

    @property
    def n_x(self) -> int:
        return self.joints.layout.n_x

    @property
    def n_coordinates(self) -> int:
        return self.joints.layout.n_theta

    @property
    def n_cut(self) -> int:
        return self.joints.n_cut

    def _data(self, d):
        """The joint functions' trailing input at the model data d."""
        return self.joints.data(d) if self.joints.data is not None else d

    def ode(self, t, x, d, z=None, mask=None):
        if not self.n_cut:
            return self.joints.dynamics(t, x, self._data(d))
        return self.joints.dynamics(t, x, z, mask, self._data(d))[0]

    @cached_property
    def _forced(self) -> ca.Function:
        if self.n_cut:
            raise UsageError("the joint formulation offers the ODE with efforts as an input "
                             "for a tree only; this model has loop closures (use its ode, "
                             "with the efforts as the model's motors)")
        return forced_ode(self.ir, self.joints.tree, self.symbols)

    def forced(self, t, x, tau, d):
        return self._forced(t, x, tau, self._data(d))

    def closure(self, t, x, d) -> tuple:
        m = self.n_cut
        if not m:
            return ca.SX(0, 1), ca.SX(0, 1)
        alg = self.joints.dynamics(t, x, ca.SX.zeros(2 * m), ca.DM.zeros(m), self._data(d))[1]
        return alg[:m], alg[m:]

    def multipliers(self, t, x, d, kept) -> ca.SX:
        m = self.n_cut
        if not m:
            return ca.SX(0, 1)
        matrix, base = self.joints.acceleration_system(t, x, self._data(d))
        kept = list(kept)
        lam = ca.SX.zeros(m, 1)
        if kept:
            lam[kept] = -ca.solve(matrix[kept, kept], base[kept])
        return ca.vertcat(lam, ca.SX.zeros(m, 1))

    def invariants(self, x) -> ca.SX:
        lay, rows = self.joints.layout, []
        for k, joint in enumerate(self.joints.tree.joints):
            for start in MOTIONS[joint.type].quaternions:
                slots = [lay.theta[k][lay.free_theta[k].index(s)]
                         for s in range(start, start + 4) if s in lay.free_theta[k]]
                if len(slots) == 4:
                    rows.append(ca.sumsqr(x[slots]) - 1)
        return ca.vertcat(*rows) if rows else ca.SX(0, 1)

    def periodic(self) -> list[int]:
        """A revolute joint's angle, not a quaternion's component or a displacement: read
        off the joint type's rotation and translation at a sample coordinate and 2 pi on."""
        lay, found = self.joints.layout, []
        for k, joint in enumerate(self.joints.tree.joints):
            motion = MOTIONS[joint.type]
            inside = {start + i for start in motion.quaternions for i in range(4)}
            base = np.full(motion.n_q, 0.3)
            for slot, c in zip(lay.theta[k], lay.free_theta[k], strict=True):
                if c in inside:
                    continue
                turned = base.copy()
                turned[c] += 2 * np.pi
                (p, p_turned), (r, r_turned) = ((np.array(ca.DM(f(v))) for v in (base, turned))
                                                for f in (motion.rotation, motion.translation))
                same = np.allclose(r, r_turned, rtol=0, atol=1e-9) and (  # p: -p, the same
                    np.allclose(p, p_turned, rtol=0, atol=1e-9)
                    or np.allclose(p, -p_turned, rtol=0, atol=1e-9))
                found += [slot] if same else []
        return found

    def _bound(self, function: ca.Function, d) -> ca.Function:
        """`function` with its trailing input fixed to the joint data at the model data d."""
        data = self._data(d)
        inputs = [ca.SX.sym(function.name_in(k), function.sparsity_in(k))
                  for k in range(function.n_in() - 1)]
        return ca.Function(function.name(), inputs, function.call([*inputs, data]),
                           function.name_in()[:-1], function.name_out())

    def state(self, q, q_dot, d) -> np.ndarray:
        relative = self._bound(self.joints.relative_states, d)
        return from_relative(self.joints.tree, *(np.array(v.full())
                                                 for v in relative(q, q_dot)))

    def independent(self, t, x, d) -> np.ndarray:
        if not self.n_cut:
            return np.ones(0)
        jacobian = self._bound(self.joints.velocity_jacobian, d)(t, x)
        return np.array(independent_rows(np.array(jacobian.full()), ASSEMBLY.linear_algebra),
                        float)

    def signs(self, t, x, q, d) -> np.ndarray:
        nb = self.ir.n_bodies
        motion = self._bound(self.joints.motion, d)
        tree_q = np.array(motion(t, x, np.zeros(2 * self.n_cut), np.ones(nb))[0].full())
        return continuing_signs(tree_q, q, nb)

    def body(self, t, x, z, signs, d) -> tuple:
        return tuple(self.joints.motion(t, x, z, signs, self._data(d)))[:4]
