"""The elements of a DAE residual (formulations.residuals): one per joint (its rows), one per body,
one per force element, each a group of instances of a kernel of formulations.residual_kernels
with the index tables that gather its unknowns from u = [x; z] and add its outputs into the
residual, and its data (numerics.element_sums.Group).

Layout (formulations.dae): x = [q; v], z = [v_dot; lam (; mu)], p = [t0; w; s (; s_phi)],
t = t0 + tau, u = [x; z]; residual [ode; alg] = [q_dot (+ Phi_q^T mu); v_dot; M v_dot + P^T lam -
F; per-row terms]. rp: v = q_dot (7 per body), every row of Phi in P; romega: v = [r_dot;
omega_bar] (6 per body), P the joint rows of [Phi_r, Pi_bar], Phi (for ggl) all rows.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.equations import body, body_kernels, evaluation, force_kernels, row_kernels, rows
from casmech.equations.derivatives import GROUND_POSE
from casmech.equations.evaluation import Evaluation
from casmech.formulations import residual_kernels as kernels
from casmech.model.ir import GROUND_INDEX, ModelIR
from casmech.numerics.element_sums import DROPPED, Group


class Indices:
    """Positions in u = [q; v; v_dot; lam (; mu)] and in the residual [ode_q; ode_v; alg_v;
    alg rows...] of one DAE. Ground's coordinates point past u, into the padding
    [GROUND_POSE; zeros(7)]; its residual rows are DROPPED."""

    def __init__(self, ir: ModelIR, form: str, kind: str):
        self.form, self.kind = form, kind
        self.layout = rows.Layout(ir.n_bodies)
        self.n_q = 7 * ir.n_bodies
        self.n_v = kernels.BODY_V[form] * ir.n_bodies
        self.joint_rows = len(ir.primitives)
        self.m = self.joint_rows + (ir.n_bodies if form == "rp" else 0)  # rows of P
        self.n_phi = self.joint_rows + ir.n_bodies  # rows of Phi (ggl's mu)
        self.n_x = self.n_q + self.n_v
        self.n_z = self.n_v + self.m + (self.n_phi if kind == "ggl" else 0)
        self.n_u = self.n_x + self.n_z
        self.n_p = 1 + 2 * self.m + (self.n_phi if kind == "ggl" else 0)  # dae.parameters
        self.padding = ca.DM(np.concatenate([GROUND_POSE, np.zeros(7)]))

    def constants(self, p) -> list:
        """The row constants in p = [t0, w, s (, s_phi)]: [w, s (, s_phi)]."""
        m = self.m
        return [p[1:1 + m], p[1 + m:1 + 2 * m]] + (
            [p[1 + 2 * m:self.n_p]] if self.kind == "ggl" else [])

    def _v(self, body: int) -> list[int]:
        return self.layout.q(body) if self.form == "rp" else self.layout.v(body)

    def q(self, body: int) -> list[int]:
        return list(range(self.n_u, self.n_u + 7)) if body == GROUND_INDEX \
            else self.layout.q(body)

    def v(self, body: int, derivative: bool = False) -> list[int]:
        """v (or v_dot) of a body in u; ground: the zero padding."""
        width = kernels.BODY_V[self.form]
        if body == GROUND_INDEX:
            return list(range(self.n_u + 7, self.n_u + 7 + width))
        return [self.n_q + (self.n_v if derivative else 0) + i for i in self._v(body)]

    def lam(self, row: int) -> int:
        return self.n_q + 2 * self.n_v + row

    def mu(self, row: int) -> int:
        return self.n_q + 2 * self.n_v + self.m + row

    def ode_q(self, body: int) -> list[int]:
        return [DROPPED] * 7 if body == GROUND_INDEX else self.layout.q(body)

    def ode_v(self, body: int) -> list[int]:
        return [self.n_q + i for i in self._v(body)]

    def alg_v(self, body: int) -> list[int]:
        return [DROPPED] * kernels.BODY_V[self.form] if body == GROUND_INDEX \
            else [self.n_x + i for i in self._v(body)]

    def alg(self, row: int, block: int) -> int:
        """Residual row of a constraint row: block 0 (Phi for ggl, else the acceleration
        row; rows of Phi: joint rows, then normalization), block 1 (ggl's P v - nu)."""
        return self.n_x + self.n_v + (row if block == 0 else self.n_phi + row)


def _all(indices, bodies) -> list[int]:
    return [i for b in bodies for i in indices(b)]


# --- joints ---------------------------------------------------------------------------------

def joint_groups(ir: ModelIR, ix: Indices, t, constants: list, ev: Evaluation) -> list[Group]:
    out = []
    for joint_keys, members in rows.by_joint_keys(ir).items():
        inputs, outputs = [], []
        for joint_rows in members:
            bodies = ir.primitives[joint_rows[0]].bodies
            x, v = _all(ix.q, bodies), _all(ix.v, bodies)
            if ix.kind == "ggl":
                inputs.append(x + v + [ix.lam(k) for k in joint_rows]
                              + [ix.mu(k) for k in joint_rows])
                outputs.append(_all(ix.ode_q, bodies) + _all(ix.alg_v, bodies)
                               + [ix.alg(k, 0) for k in joint_rows]
                               + [ix.alg(k, 1) for k in joint_rows])
            else:
                inputs.append(x + v + _all(lambda b: ix.v(b, True), bodies)
                              + [ix.lam(k) for k in joint_rows])
                outputs.append(_all(ix.alg_v, bodies) + [ix.alg(k, 0) for k in joint_rows])
        out.append(Group(kernels.joint(joint_keys, ix.form, ix.kind), np.array(inputs),
                         np.array(outputs), _joint_data(ir, joint_keys, members, t, constants,
                                                        ev)))
    return out


def _joint_data(ir: ModelIR, keys: tuple, members: list[list[int]], t, constants: list,
                ev: Evaluation):
    """d of every instance (columns): each row constant (w, s, s_phi) by one gather, f
    constant unless a row's f depends on time, the vectors of rows whose kernels do not bake
    them."""
    count, r = len(members), len(keys)
    flat = [k for joint_rows in members for k in joint_rows]
    gathered = [ca.reshape(vector[flat], r, count) for vector in constants]
    values = [row_kernels.f_constant(ir.primitives[k]) for k in flat]
    if any(key.f_class == row_kernels.TIME for key in keys) or any(
            isinstance(v, ca.SX) for v in values):
        f = rows.joint_f(ir, keys, members, t, ev)
    else:
        f = ca.DM(np.array([[v, 0.0, 0.0] for v in values]).reshape(count, 3 * r).T)
    vectors = rows.joint_vectors(ir, keys, members,
                                 lambda key: row_kernels.constraint(key).sparsity_in(1),
                                 lambda key: key.values is None)
    size = len(vectors[0])
    data = ev.constant(rows.stacked(vectors)) if size else ca.DM(0, count)
    return ca.vertcat(*gathered, f, data)


# --- bodies ---------------------------------------------------------------------------------

def body_group(ir: ModelIR, ix: Indices, constants: list, ev: Evaluation) -> list[Group]:
    nb = ir.n_bodies
    if not nb:
        return []
    rp, ggl = ix.form == "rp", ix.kind == "ggl"
    inputs, outputs = [], []
    for k in range(nb):
        row = ix.joint_rows + k  # its normalization row
        inputs.append(ix.q(k) + ix.v(k) + ix.v(k, True) + ([ix.lam(row)] if rp else [])
                      + ([ix.mu(row)] if ggl else []))
        outputs.append(ix.ode_q(k) + ix.ode_v(k) + ix.alg_v(k)
                       + ([ix.alg(row, 0)] if rp or ggl else [])
                       + ([ix.alg(row, 1)] if rp and ggl else []))
    normalization = slice(ix.joint_rows, ix.joint_rows + nb)
    chosen = constants if rp else constants[2:]  # r-omega: s_phi alone (ggl), or none
    data = [ca.reshape(vector[normalization], 1, nb) for vector in chosen]
    data += [body_kernels.masses(ir, ev), nonzeros(body_kernels.inertias(ir, ev))]
    gravity = body_kernels.gravity_constant(ir)
    if gravity is None:  # model data: every body's column repeats it
        data.append(ca.repmat(ev.constant(ca.vertcat(*evaluation.entries(ir.gravity))), 1, nb))
    kernel = kernels.body(body_kernels.inertia_pattern(ir), gravity, ix.form, ix.kind)
    return [Group(kernel, np.array(inputs), np.array(outputs), ca.vertcat(*data))]


def nonzeros(c):
    """The (nnz x count) values of a (pattern x count) matrix with the same pattern per
    column."""
    if c.nnz() == 0:
        return ca.DM(0, c.size2())
    values = c.nz[:] if isinstance(c, (ca.MX, ca.SX)) else ca.DM(c.nonzeros())
    return ca.reshape(values, c.nnz() // c.size2(), c.size2())


# --- force elements -------------------------------------------------------------------------

def force_groups(ir: ModelIR, ix: Indices, t, ev: Evaluation) -> list[Group]:
    by_key, plain = force_kernels.instances(ir)
    out = [_unrolled_force(ir, ix, force, t, ev) for force in plain]
    for key, members in by_key.items():
        kernel = kernels.force(force_kernels.kernel(key, members[0].actuator), ix.form)
        width = kernel.size1_out(0)
        inputs = [_all(ix.q, (f.body_i, f.body_j)) + _all(ix.v, (f.body_i, f.body_j))
                  for f in members]
        outputs = [_all(ix.alg_v, (f.body_i, f.body_j))[:width] for f in members]
        data, values = force_kernels.group_data(key, members, t, ev)
        out.append(Group(kernel, np.array(inputs), np.array(outputs),
                         ca.vertcat(ca.repmat(t, 1, len(members)), ca.DM(data.T),
                                    nonzeros(values))))
    return out


def _unrolled_force(ir: ModelIR, ix: Indices, force, t, ev: Evaluation) -> Group:
    """An element without a kernel (equations.force_kernels.unrolled, over every coordinate):
    its own kernel over the coordinates and velocities its -F depends on; d = [t (; the model
    data)]."""
    function = force_kernels.unrolled(ir, force, ev.data)
    tt, q, _, *data = function.sx_in()
    nb = ir.n_bodies
    v = ca.SX.sym("v", ix.n_v)
    if ix.form == "rp":
        q_dot, per_body = v, None
    else:
        per_body = [q[3 * nb + 4 * k:3 * nb + 4 * k + 4] for k in range(nb)]
        q_dot = ca.vertcat(v[:3 * nb], *[body.p_dot(p, v[3 * nb + 3 * k:3 * nb + 3 * k + 3])
                                          for k, p in enumerate(per_body)])
    generalized = function(tt, q, q_dot, *data)[0]
    if per_body is not None:
        generalized = ca.vertcat(generalized[:3 * nb], *[
            body.moment(p, generalized[3 * nb + 4 * k:3 * nb + 4 * k + 4])
            for k, p in enumerate(per_body)])
    variables = ca.vertcat(q, v)
    columns = sorted(set(ca.jacobian(generalized, variables).sparsity().get_col()))
    out_rows = sorted(set(ca.sparsify(generalized).sparsity().row())) or [0]
    y = ca.SX.sym("y", len(columns))
    value = -generalized[out_rows]
    if columns:
        value = ca.substitute(value, variables[columns], y)
    kernel = ca.Function(f"element_{ix.form}_{function.name()}", [y, ca.vertcat(tt, *data)],
                         [value], ["y", "d"], ["out"])
    return Group(kernel, np.array([columns], dtype=int).reshape(1, len(columns)),
                 np.array([[ix.n_x + r for r in out_rows]]),
                 ca.vertcat(t, *([ev.input] if data else [])))
