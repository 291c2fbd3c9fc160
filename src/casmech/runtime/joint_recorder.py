"""The results rows of a joint-coordinate run (runtime.joint_dynamics): the r-p state the
tree gives and every joint row's multiplier, the loops' from the integrator's algebraic
states or solved at each row's state (runtime.joint_rows), the minimum-norm ones where loop
rows were masked (as the r-p DAE reports them); every row of a block by one mapped call."""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from casmech.equations.functions import SystemFunctions
from casmech.formulations.joint_system import JointSystem, saddle_terms
from casmech.runtime.buffers import ColumnCall
from casmech.runtime.nonfinite import all_finite
from casmech.runtime.row_calls import over_rows, rows_of
from casmech.runtime.workspace import Workspace

if TYPE_CHECKING:  # (the loops' rows are imported where a tree with loops records them)
    from casmech.runtime.joint_rows import LoopRows


class Recorder:
    """Appends results rows: the r-p state of the tree and every joint's multipliers (the
    minimum-norm ones where loop rows were masked, as the r-p DAE reports them), every row of
    a block by one mapped call."""

    def __init__(self, functions: SystemFunctions, system: JointSystem, signs, mask,
                 workspace: Workspace, solve_loops: bool = False):
        # (the bundle is not held: a Recorder is kept with its start in the workspace)
        self.system, self.signs = system, signs
        self.workspace, self._call = workspace, None
        self.least_norm = workspace.kept(
            "joint_least_norm", (mask.tobytes(), system.dynamics),
            lambda: ColumnCall(_least_norm(functions, system, mask))) if mask.any() else None
        # with solve_loops (the loop_rows option), a system over functions.ir, its own or a
        # parametric library's bound to the IR's values (not a controller's, whose forces
        # that IR does not hold): its loop rows solved at each row's state
        solved = solve_loops and system.n_cut and (functions.joint_functions is None
                                                    or functions.parametric is not None)
        self.loops = workspace.kept("joint_loop_rows", (mask.tobytes(), system.dynamics),
                                    lambda: _loop_rows(functions, system, mask)) if solved else None

    @classmethod
    def kept(cls, derived: dict, functions: SystemFunctions, system: JointSystem, signs, mask,
             workspace: Workspace, solve_loops: bool = False) -> Recorder:
        """The Recorder of a kept start, in its `derived` entries by solve_loops
        (runtime.joint_dynamics._kept_start: signs, mask and system are the start's)."""
        found = derived.get(("recorder", solve_loops))
        if found is None:
            found = derived["recorder", solve_loops] = cls(functions, system, signs, mask,
                                                           workspace, solve_loops)
        return found

    def first(self, t0: float, x, z, kept: dict) -> tuple[tuple[np.ndarray, ...], bool]:
        """The rows at t0 of a run from a kept start (x, z) and whether they are all finite:
        kept in that start's `kept` under ("first", whether loop rows are solved) (the rest of
        a row is a function of the start) as one vector with that answer, handed out as views
        of one copy of it (one copy; a check of them sums that copy alone:
        runtime.nonfinite.shared)."""
        key = "first", self.loops is not None
        found = kept.get(key)
        if found is None:
            rows = self.rows([t0], np.asarray(x)[:, None], np.asarray(z)[:, None])
            ends = np.cumsum([row.shape[1] for row in rows]).tolist()
            vector = np.concatenate([row.ravel() for row in rows])
            found = kept[key] = vector, ends, all_finite(vector)
        vector, (a, b, c, _), finite = found
        row = vector.copy()
        return (row[None, :a], row[None, a:b], row[None, b:c], row[None, c:]), finite

    def _mapped(self):
        """The results rows' function over many states (joint_rows.over_rows; kept in the
        workspace, looked up once per run)."""
        if self._call is None:
            self._call = self.workspace.kept("joint_motion_maps", self.system.motion,
                                             lambda: over_rows(self.system.motion))
        return self._call

    def rows(self, times, states, algebraic):
        """(q, q_dot, q_ddot, lam), one row per time; with loops, their multipliers solved at
        each row's state (runtime.joint_rows) where the system was built over the bundle's IR,
        else the integrator's `algebraic` states."""
        times = np.asarray(times, float)
        if self.loops is not None:
            q, q_dot, q_ddot, lam = self.loops.by_row(times, np.asarray(states, float),
                                                      self.signs)
        else:
            q, q_dot, q_ddot, lam = rows_of(self._mapped(), times, np.asarray(states, float).T,
                                            np.asarray(algebraic, float).T, self.signs)
        if self.least_norm is not None:
            (lam,) = self.least_norm(times[None, :], q.T, lam.T)
            lam = lam.T
        return q, q_dot, q_ddot, lam


def _loop_rows(functions: SystemFunctions, system: JointSystem, mask) -> LoopRows:
    """The loops' rows solved at each state (runtime.joint_rows): the compiled library's where
    it holds them, else solved_motion of the saddle terms and the system's motion (SX, or a
    parametric library's motion called through MX)."""
    from casmech.runtime.joint_rows import LoopRows, solved_motion

    def terms() -> ca.Function:
        return saddle_terms(functions.ir, system.tree)

    if system.solved_motion is not None:  # the terms only for a singular column
        return LoopRows(system.solved_motion, terms, system.motion, mask)
    built = terms()
    return LoopRows(solved_motion(built, system.motion), lambda: built, system.motion, mask)


def _least_norm(functions: SystemFunctions, system: JointSystem, mask) -> ca.Function:
    """(t, q, lam) -> lam with the joint rows' least-norm multipliers (runtime.dynamics'
    minimum_norm over the r-omega Jacobian; the masked cut rows depend on the rest)."""
    from casmech.runtime.dae_rows import minimum_norm

    n = functions.n_joint_rows
    masked = {system.cut_rows[k] for k in np.flatnonzero(mask)}
    keep = [row for row in range(n) if row not in masked]
    t, q = ca.MX.sym("t"), ca.MX.sym("q", functions.n_coordinates)
    lam = ca.MX.sym("lam", functions.n_rows)
    jacobian = functions["romega_jacobian"](t, q)
    joint = minimum_norm(jacobian, lam[:n], keep)
    return ca.Function("least_norm", [t, q, lam], [ca.vertcat(joint, lam[n:])])
