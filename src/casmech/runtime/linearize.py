"""The linear model at any state (t, q, q_dot) of a run, and the generalized forces of inputs.

Independent coordinates (the chart of runtime/modal.py at the equilibrium, here at any q*):
z = N^T (q - q*) for q on Phi = 0 near q*, and w = N^T q_dot, N the orthonormal null-space basis
of Phi_q(t*, q*) (statics.null_space). The state x = [z; w] obeys x' = f(x, u, t):

    z' = w,   w' = N^T q_ddot(q, q_dot, u),
    q = q* + N z (to first order, all that A needs),  q_dot: [Phi_I(q); N^T] q_dot = [nu_I; w],
    [M(q) Phi_I^T; Phi_I 0] [q_ddot; lam_I] = [Q(t, q, q_dot) + G(q) u; gamma_I(t, q, q_dot)],

with I the independent constraint rows at q* (the column-pivoted QR's pivots: redundant rows
dropped, so both matrices are square; the saddle system is numerics.kkt.saddle's). A = df/dx and
B = df/du at (x*, 0, t*) come from CasADi's forward AD through this graph (MX, the linear solves
included): the velocity terms (Coriolis, gyroscopic, the constraint curvature with
q_dot* != 0) are in it. Away from an equilibrium a
linearization depends on the coordinates: these describe perturbations measured as N^T dq, and
the chart's curvature enters A with q_dot*^2 (docs/analyses.md#modal). At an equilibrium
(q_dot* = 0, q_ddot* = 0) A and B equal runtime/modal.py's reduced M, C, K form.

Inputs u: what an element's own force law would add, each by AD of that element's generalized
force with its law replaced by an input symbol (INPUT_KINDS): an effort motor's torque or force
(`<joint>.torque` / `.force`), a tsda's or rsda's tension (`.force` / `.torque`, the sign of its
spring force and `actuator:`: positive pulls the points together, turns body j back), a point
force's or torque's components in its frame (`.fx .fy .fz` / `.tx .ty .tz`), a bushing's force and
torque on body_j in its frame (`.fx .fy .fz .tx .ty .tz`, as its preload).
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca
import numpy as np

from casmech.equations.assemble import Coordinates
from casmech.equations.eom import FORCE_ELEMENTS, INPUT_KINDS
from casmech.equations.functions import SystemFunctions, all_sx, build_functions
from casmech.model.ir import ForceIR
from casmech.numerics import kkt
from casmech.runtime.workspace import Workspace, of


def input_elements(functions: SystemFunctions, names: Sequence[str] | None) -> list[ForceIR]:
    """The elements named (effort-motor joints, then force elements of that name), in order;
    None: every effort motor."""
    ir = functions.ir
    if names is None:
        return list(ir.motors)
    found = []
    for name in names:
        found += [e for e in (*ir.motors, *ir.forces) if e.name == name and e.type in INPUT_KINDS]
    return found


def input_forces(functions: SystemFunctions, names: Sequence[str] | None = None
                 ) -> tuple[list[str], ca.Function]:
    """(input names, G: (t, q, q_dot) -> n x inputs, the generalized force per unit input)."""
    x = Coordinates.create(functions.n_bodies)
    labels, columns = [], []
    for element in input_elements(functions, names):
        suffixes, with_inputs = INPUT_KINDS[element.type]
        u = ca.SX.sym("u", len(suffixes))
        generalized = FORCE_ELEMENTS[element.type](with_inputs(element, u), x)[0]
        columns.append(x.ground_fixed(ca.jacobian(generalized, u)))
        labels += [f"{element.name}.{suffix}" for suffix in suffixes]
    matrix = ca.horzcat(*columns) if columns else ca.SX(x.q.numel(), 0)
    return labels, ca.Function("input_forces", [x.t, x.q, x.q_dot], [matrix])


def sx_bundle(functions: SystemFunctions, workspace: Workspace | None = None
              ) -> SystemFunctions:
    """The bundle as SX functions (a compiled bundle's model rebuilt once per workspace for
    AD)."""
    if all_sx(functions.functions):
        return functions
    return of(functions, workspace).one("sx_bundle", lambda: build_functions(functions.ir))


def state_space(functions: SystemFunctions, t: float, q: np.ndarray, q_dot: np.ndarray,
                basis: np.ndarray, rows: Sequence[int], inputs: ca.Function,
                workspace: Workspace | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of x = [z; w] at (t, q, q_dot) (module docstring); `rows` the independent rows
    of Phi_q there, `inputs` the G of input_forces."""
    bundle = sx_bundle(functions, workspace)
    k, count = basis.shape[1], inputs.size2_out(0)
    z, w, u = ca.MX.sym("z", k), ca.MX.sym("w", k), ca.MX.sym("u", count)
    n_basis = ca.DM(basis)
    position = ca.DM(q) + ca.mtimes(n_basis, z)
    rows = list(rows)
    phi_q = bundle["phi_q"](t, position)[rows, :]
    velocity = ca.solve(ca.vertcat(phi_q, n_basis.T),
                        ca.vertcat(bundle["nu"](t, position)[rows], w))
    forces = bundle["generalized_forces"](t, position, velocity) + ca.mtimes(
        inputs(t, position, velocity), u)
    mass = bundle["mass_matrix"](position)
    saddle = kkt.saddle(mass.sparsity(), phi_q.sparsity())
    acceleration, _ = saddle(mass, phi_q, forces, bundle["gamma"](t, position, velocity)[rows],
                             ca.DM.zeros(len(rows)))
    f = ca.vertcat(ca.mtimes(n_basis.T, velocity), ca.mtimes(n_basis.T, acceleration))
    # forward AD in every direction at once: quicker to build than ca.jacobian of the MX graph
    # (docs/decisions/linearization.md)
    ode = ca.Function("chart_ode", [z, w, u], [f])
    x = [np.zeros(k), basis.T @ q_dot, np.zeros(count)]
    seeds = np.eye(2 * k + count)
    columns = ode.forward(2 * k + count)(*x, ode(*x), seeds[:k], seeds[k:2 * k], seeds[2 * k:])
    columns = np.array(columns).reshape(2 * k, 2 * k + count)
    return columns[:, :2 * k], columns[:, 2 * k:]
