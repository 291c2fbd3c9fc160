"""The CasADi Functions an FMU's C calls, over the state x = [theta; u] of the joint
formulation and jd, the joint functions' data (the registered joint formulation's equations
over fmu.model's IR, FORMULATIONS["joint"].equations: [d; inputs; the tree's constants]). The
states are named as the formulation's `states` name them (`<joint>.angle`, ...: the joint's
results columns where they are its states).

    data(theta) -> jd                  the model data at the parameters (inputs at their start)
    ode(t, x, jd) -> x_dot             the ODE (below)
    outputs(t, x, jd) -> y             the results columns chosen (fmu.outputs)
    file_pose(jd) -> q_ref             the file's initial pose (r-p) at the parameters
    tree_pose(t, x, jd) -> q           the r-p pose of the tree
    position_terms(t, x, jd, q_ref)    the closest-point problem's terms at x (below)
    velocity_terms(t, x, jd)           the closest-velocity problem's terms at x
    drift(t, x, jd) -> (position, velocity)  the largest loop-closure residuals
    calculated(theta) -> values        the calculated parameters

A tree's ODE is joint_system's (theta' = theta_dot, u' from the articulated-body algorithm).
A mechanism with loops: the same ODE with the cut joints' multipliers solved from the
acceleration-level closure (the accelerations are affine in them: joint_system's
acceleration_system), the rows dependent at t0 masked out as the joint DAE masks them. That
ODE keeps the closures' second derivative at zero, so positions and velocities drift slowly
off the closures; the FMU projects the state back (closest point, as at the start) when the
drift passes a tolerance: Model Exchange at a step event (fmi2CompletedIntegratorStep asks
for one), Co-Simulation after an integrator step.

The start and the projection solve `casmech run`'s assembly problem in joint coordinates:
positions min |q(theta) - q_ref|^2 (Euclidean in the r-p coordinates q, as
runtime.assembly's closest point) subject to the kept closure rows and each quaternion
coordinate's unit norm, by Gauss-Newton steps on the KKT system; velocities min
|q_dot(theta, u) - q_dot_ref|^2 subject to the closures' velocity rows (q_dot_ref the file's
velocities, or the current ones for a projection), one linear solve. These functions give the
residuals and Jacobians; the C forms and solves the KKT systems (casmech_fmu_solver.c: dense
LU with partial pivoting), whose symbolic solution would grow as the cube of the coordinates.
The tree's poses satisfy every tree joint's constraints by construction, so on a tree this is
exactly the closest point of the r-p assembly, and at the model's own values it is solved at
the start state computed by casmech (fmu.start).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.core.records import record
from casmech.elements.joint_types import MOTIONS
from casmech.equations.functions import SystemFunctions, build_functions
from casmech.fmu import outputs
from casmech.fmu.model import Exported
from casmech.fmu.start import Start
from casmech.formulations.registry import FORMULATIONS


@record
class FmuSystem:
    functions: dict[str, ca.Function]  # the C functions by name (module docstring)
    state_names: tuple[str, ...]
    output_names: tuple[str, ...]
    n_jd: int
    input_offset: int  # where the inputs sit in jd
    loops: bool
    n_theta: int  # joint coordinates among the states (then velocities)
    position_rows: int  # constraints of the position problem (closure rows, unit quaternions)
    velocity_rows: int  # constraints of the velocity problem (closure rows)


def _function(name: str, inputs: dict, results: dict) -> ca.Function:
    return ca.Function(name, list(inputs.values()), list(results.values()), list(inputs),
                       list(results))


class _Builder:
    """The symbols and shared expressions of the functions (module docstring)."""

    def __init__(self, exported: Exported, begin: Start):
        self.exported, self.begin = exported, begin
        ir = exported.ir
        self.formulation = FORMULATIONS["joint"]
        self.system = self.formulation.equations(ir, exported.data)
        self.tree = self.system.tree
        self.bundle: SystemFunctions = build_functions(ir, exported.data)
        lay = self.system.layout
        self.n_theta, self.n_x = lay.n_theta, lay.n_x
        self.n_jd = self.system.dynamics.size1_in(self.system.dynamics.n_in() - 1)
        self.n_data = exported.n_data + exported.u.numel()
        self.t, self.x = ca.SX.sym("t"), ca.SX.sym("x", self.n_x)
        self.jd = ca.SX.sym("jd", self.n_jd)
        m = self.system.n_cut
        self.mask = np.asarray(begin.mask, float)
        self.keep = [k for k in range(m) if self.mask[k] == 0]
        self.signs = ca.DM(begin.signs)
        self.z = self._multipliers() if m else ca.SX(0, 1)

    @property
    def data(self):
        """[d; u]: the bundle's trailing input, the head of jd."""
        return self.jd[:self.n_data]

    def _multipliers(self) -> ca.SX:
        """z = [lam; mu = 0] with lam making the kept closure rows' accelerations vanish."""
        m = self.system.n_cut
        matrix, base = self.system.acceleration_system(self.t, self.x, self.jd)
        lam = ca.SX.zeros(m)
        if self.keep:
            lam[self.keep] = ca.solve(matrix[self.keep, self.keep], -base[self.keep])
        return ca.vertcat(lam, ca.SX.zeros(m))

    def ode(self) -> ca.SX:
        if not self.system.n_cut:
            return self.system.dynamics(self.t, self.x, self.jd)
        return self.system.dynamics(self.t, self.x, self.z, ca.DM(self.mask), self.jd)[0]

    def motion(self, x=None) -> list:
        """(q, q_dot, q_ddot, lam) of the results row at x (lam: the minimum-norm ones where
        closure rows are masked, as runtime.joint_dynamics reports them)."""
        x = self.x if x is None else x
        z = self.z if x is self.x else ca.SX.zeros(self.z.shape)
        q, q_dot, q_ddot, lam = self.system.motion(self.t, x, z, self.signs, self.jd)
        if self.mask.any():
            lam = self._least_norm(q, lam)
        return [q, q_dot, q_ddot, lam]

    def _least_norm(self, q, lam):
        n = self.bundle.n_joint_rows
        masked = {self.system.cut_rows[k] for k in np.flatnonzero(self.mask)}
        keep = [r for r in range(n) if r not in masked]
        jacobian = self.bundle["romega_jacobian"](self.t, q, self.data)
        kept = jacobian[keep, :]
        gram = kept @ kept.T
        y = ca.solve(gram, kept @ (jacobian.T @ lam[:n]))
        c = ca.solve(gram, kept @ jacobian.T).T
        return ca.vertcat(c @ ca.solve(c.T @ c, y), lam[n:])

    def closure(self, x):
        """(the kept cut rows of Phi, of Phi_q q_dot - nu) at the tree's state x."""
        if not self.keep:
            return ca.SX(0, 1), ca.SX(0, 1)
        q, q_dot = self.system.motion(self.t, x, ca.SX.zeros(self.z.shape), self.signs,
                                      self.jd)[:2]
        rows = [self.system.cut_rows[k] for k in self.keep]
        phi = self.bundle["phi"](self.t, q, self.data)[rows]
        rate = (self.bundle["phi_q"](self.t, q, self.data) @ q_dot
                - self.bundle["nu"](self.t, q, self.data))[rows]
        return phi, rate

    def unit_quaternions(self) -> ca.SX:
        """|e|^2 - 1 of every quaternion block among the free coordinates."""
        rows = []
        lay = self.system.layout
        for joint, slots, free in zip(self.tree.joints, lay.theta, lay.free_theta, strict=True):
            for start in MOTIONS[joint.type].quaternions:
                if all(c in free for c in range(start, start + 4)):
                    block = [slots[free.index(c)] for c in range(start, start + 4)]
                    rows.append(ca.sumsqr(self.x[block]) - 1)
        return ca.vertcat(ca.SX(0, 1), *rows)

    def position_terms(self) -> tuple[ca.SX, dict]:
        """(q_ref, the position problem at x: residual q(theta) - q_ref and its Jacobian by
        theta, the constraints (kept closure rows, unit quaternions) and theirs)."""
        theta = self.x[:self.n_theta]
        q_ref = ca.SX.sym("q_ref", 7 * self.exported.ir.n_bodies)
        q = self.system.motion(self.t, self.x, ca.SX.zeros(self.z.shape), self.signs,
                               self.jd)[0]
        residual = q - q_ref
        constraints = ca.vertcat(self.closure(self.x)[0], self.unit_quaternions())
        return q_ref, {"jacobian": ca.jacobian(residual, theta), "residual": residual,
                       "rows": ca.jacobian(constraints, theta), "values": constraints}

    def velocity_terms(self) -> dict:
        """The velocity problem at x: q_dot = jacobian u + base, the closures' velocity rows
        rows u + values = 0, and the file's initial velocities as r-p rates at q."""
        u = self.x[self.n_theta:]
        q, q_dot = self.system.motion(self.t, self.x, ca.SX.zeros(self.z.shape), self.signs,
                                      self.jd)[:2]
        zero = ca.SX.zeros(u.shape)
        rate = self.closure(self.x)[1]
        return {"jacobian": ca.jacobian(q_dot, u), "base": ca.substitute(q_dot, u, zero),
                "rows": ca.jacobian(rate, u), "values": ca.substitute(rate, u, zero),
                "file": self.file_velocities(q)}

    def from_data(self, expression):
        """An expression of the IR's numbers (the symbols d) with d read from jd."""
        return ca.substitute(expression, self.exported.split.symbols,
                             self.data[:self.exported.n_data])

    def file_velocities(self, q):
        """The file's initial velocities as r-p rates at the pose q (runtime.assembly's
        file_velocities)."""
        ir, nb = self.exported.ir, self.exported.ir.n_bodies
        r_dot = [ca.SX(b.r_dot0) for b in ir.bodies]
        p_dot = [0.5 * euler.e_matrix(q[3 * nb + 4 * k:3 * nb + 4 * k + 4]).T @ ca.SX(b.omega0)
                 for k, b in enumerate(ir.bodies)]
        return self.from_data(ca.vertcat(ca.SX(0, 1), *r_dot, *p_dot))

    def file_pose(self):
        ir = self.exported.ir
        return self.from_data(ca.vertcat(ca.SX(0, 1), *(ca.SX(b.r0) for b in ir.bodies),
                                         *(ca.SX(b.p0) for b in ir.bodies)))


def build_system(exported: Exported, begin: Start, columns: list[int]) -> FmuSystem:
    """The FMU's functions (module docstring); `columns` the outputs (fmu.outputs.chosen)."""
    b = _Builder(exported, begin)
    t, x, jd = b.t, b.x, b.jd
    # x's names, the joint's results columns where they are its states (a column of the
    # same name is then read as the state)
    states = b.formulation.states(b.bundle).differential
    every = outputs.names(b.bundle)
    # a joint state column that is a state of the FMU is read as the state, not output twice
    columns = [k for k in columns if every[k] not in states]
    theta = exported.theta
    if b.n_x != len(begin.x0):
        raise AssertionError("the symbolic tree and the numeric start differ in their states")
    # the reaction frames' vectors are the IR's own numbers: entries of d, read from jd
    row = b.from_data(outputs.row(b.bundle, t, *b.motion(), b.data, exported.data))
    data = b.system.data(ca.vertcat(exported.split.expressions, ca.DM(begin.inputs)))
    q_ref, position = b.position_terms()
    phi, rate = b.closure(x)
    worst = (ca.mmax(ca.fabs(phi)), ca.mmax(ca.fabs(rate))) if phi.numel() else (
        ca.SX(0), ca.SX(0))
    functions = [
        _function("cm_data", {"theta": theta}, {"jd": data}),
        _function("cm_ode", {"t": t, "x": x, "jd": jd}, {"x_dot": b.ode()}),
        _function("cm_outputs", {"t": t, "x": x, "jd": jd}, {"y": row[columns]}),
        _function("cm_file_pose", {"jd": jd}, {"q": b.file_pose()}),
        _function("cm_tree_pose", {"t": t, "x": x, "jd": jd}, {"q": b.motion(x)[0]}),
        _function("cm_position_terms", {"t": t, "x": x, "jd": jd, "q_ref": q_ref}, position),
        _function("cm_velocity_terms", {"t": t, "x": x, "jd": jd}, b.velocity_terms()),
        _function("cm_drift", {"t": t, "x": x, "jd": jd},
                  {"position": worst[0], "velocity": worst[1]}),
        _function("cm_calculated", {"theta": theta}, {"values": exported.calculated}),
    ]
    return FmuSystem({f.name(): f for f in functions}, states,
                     tuple(every[k] for k in columns), b.n_jd, exported.n_data,
                     bool(b.system.n_cut), b.n_theta, position["values"].numel(),
                     len(b.keep))
