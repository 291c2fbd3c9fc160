"""The DAE residuals of formulations.dae (both formulations, both stabilizations) as sums of
elements (numerics.element_sums): one per joint, one per body, one per force element, whose kernels
are formulations.residual_kernels. The code does not grow with the model (only index tables do), and
the Jacobian comes from the kernels' own SX Jacobians (a small model's DAE is compiled from
formulations.dae's unrolled SX instead: oracles). Each residual is compiled as the DAE
casadi's IDAS interface integrates together with `daeF` and `jacF`, the residual and its
Jacobian blocks, which that interface takes from the DAE's library instead of building them
(so each DAE gets a library of its own: codegen.generate). Equal to formulations.dae's residuals
over the SX bundle in value and Jacobian (tests/codegen/test_residuals.py).

Layout (formulations.dae): x = [q; v], z = [v_dot; lam (; mu)], p = [t0; w; s (; s_phi)],
t = t0 + tau, u = [x; z]; residual [ode; alg] = [q_dot (+ Phi_q^T mu); v_dot; M v_dot + P^T lam - F;
per-row terms]. rp: v = q_dot (7 per body), every row of Phi in P; romega: v = [r_dot;
omega_bar] (6 per body), P the joint rows of [Phi_r, Pi_bar], Phi (for ggl) all rows.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.equations import body
from casmech.equations.assemble import GROUND_POSE
from casmech.equations.functions import build_functions
from casmech.equations.mapped import bodies, forces
from casmech.equations.mapped import rows as row_kernels
from casmech.equations.mapped.kernels import Layout, by_joint_keys, taylor_or_constant
from casmech.formulations import dae
from casmech.formulations import residual_kernels as kernels
from casmech.formulations.table import FORMULATIONS
from casmech.model.ir import GROUND_INDEX, ModelIR
from casmech.numerics.element_sums import DROPPED, ElementSum, Group

KINDS = {"ggl": "dae_ggl_", "projection": "dae_"}  # stabilization -> name prefix
# A DAE of a model of at most UNROLLED_BODIES bodies is compiled from formulations.dae's unrolled
# SX (from_residual) when its residual and Jacobian take at most UNROLLED_INSTRUCTIONS SX
# instructions together, instead of from the element kernels: there the unrolled code runs
# faster per call and builds sooner; above, it gains little and builds slower
# (docs/decisions/codegen-small-dae-unrolled.md).
UNROLLED_BODIES = 4
UNROLLED_INSTRUCTIONS = 12_000


def name(form: str, kind: str) -> str:
    return KINDS[kind] + form


class Indices:
    """Positions in u = [q; v; v_dot; lam (; mu)] and in the residual [ode_q; ode_v; alg_v;
    alg rows...] of one DAE. Ground's coordinates point past u, into the padding
    [GROUND_POSE; zeros(7)]; its residual rows are DROPPED."""

    def __init__(self, ir: ModelIR, form: str, kind: str):
        self.form, self.kind = form, kind
        self.layout = Layout(ir.n_bodies)
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
        return [p[1:1 + m], p[1 + m:1 + 2 * m]] + ([p[1 + 2 * m:]] if self.kind == "ggl" else [])

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


# --- joints ---------------------------------------------------------------------------------

def joint_groups(ir: ModelIR, ix: Indices, t, constants: list) -> list[Group]:
    out = []
    for joint_keys, members in by_joint_keys(ir).items():
        inputs, outputs = [], []
        for rows in members:
            pair = (ir.primitives[rows[0]].body_i, ir.primitives[rows[0]].body_j)
            x, v = _both(ix.q, pair), _both(ix.v, pair)
            if ix.kind == "ggl":
                inputs.append(x + v + [ix.lam(k) for k in rows] + [ix.mu(k) for k in rows])
                outputs.append(_both(ix.ode_q, pair) + _both(ix.alg_v, pair)
                               + [ix.alg(k, 0) for k in rows] + [ix.alg(k, 1) for k in rows])
            else:
                inputs.append(x + v + _both(lambda b: ix.v(b, True), pair)
                              + [ix.lam(k) for k in rows])
                outputs.append(_both(ix.alg_v, pair) + [ix.alg(k, 0) for k in rows])
        out.append(Group(kernels.joint(joint_keys, ix.form, ix.kind), np.array(inputs),
                         np.array(outputs), _joint_data(ir, joint_keys, members, t,
                                                        constants)))
    return out


def _both(indices, pair) -> list[int]:
    return [i for body in pair for i in indices(body)]


def _joint_data(ir: ModelIR, keys: tuple, members: list[list[int]], t, constants: list):
    """d of every instance (columns): each row constant (w, s, s_phi) by one gather, f
    constant unless a row's f depends on time, the vectors of rows whose kernels do not bake
    them."""
    count, r = len(members), len(keys)
    flat = [k for rows in members for k in rows]
    gathered = [ca.reshape(vector[flat], r, count) for vector in constants]
    if any(key.f_class == row_kernels.TIME for key in keys):
        f = ca.horzcat(*[ca.vertcat(*[taylor_or_constant(ir.primitives[k], key, t)
                                      for k, key in zip(rows, keys, strict=True)])
                         for rows in members])
    else:
        f = ca.DM(np.array([[row_kernels.f_constant(ir.primitives[k]), 0.0, 0.0]
                            for k in flat]).reshape(count, 3 * r).T)
    vectors = [np.concatenate([np.zeros(0)] + [
        row_kernels.vectors_of(ir.primitives[k])[list(
            row_kernels.constraint(key).sparsity_in(1).row())]
        for k, key in zip(rows, keys, strict=True) if key.values is None]) for rows in members]
    return ca.vertcat(*gathered, f, ca.DM(np.array(vectors).reshape(count, -1).T))


# --- bodies ---------------------------------------------------------------------------------

def body_group(ir: ModelIR, ix: Indices, constants: list) -> list[Group]:
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
    rows = slice(ix.joint_rows, ix.joint_rows + nb)  # the normalization rows
    chosen = constants if rp else constants[2:]  # r-omega: s_phi alone (ggl), or none
    data = [ca.reshape(vector[rows], 1, nb) for vector in chosen]
    data += [bodies.masses(ir), _nonzeros(bodies.inertias(ir))]
    kernel = kernels.body(bodies.inertia_pattern(ir), tuple(float(g) for g in ir.gravity),
                          ix.form, ix.kind)
    return [Group(kernel, np.array(inputs), np.array(outputs), ca.vertcat(*data))]


def _nonzeros(c):
    """The (nnz x count) values of a (pattern x count) matrix with the same pattern per
    column."""
    if c.nnz() == 0:
        return ca.DM(0, c.size2())
    return ca.reshape(c.nz[:] if isinstance(c, ca.MX) else ca.DM(c.nonzeros()),
                      c.nnz() // c.size2(), c.size2())


# --- force elements -------------------------------------------------------------------------

def force_groups(ir: ModelIR, ix: Indices, t) -> list[Group]:
    by_key: dict = {}
    out = []
    for force in (*ir.forces, *ir.motors, *ir.limits):  # as equations.mapped.forces.applied
        if forces.on_ground(force):
            continue
        if forces.kernelised(force):
            by_key.setdefault(forces.key_of(force), []).append(force)
        else:
            out.append(_unrolled_force(ir, ix, force, t))
    for key, members in by_key.items():
        kernel = kernels.force(forces.kernel(key, members[0].actuator), ix.form)
        width = kernel.size1_out(0)
        inputs = [_both(ix.q, (f.body_i, f.body_j)) + _both(ix.v, (f.body_i, f.body_j))
                  for f in members]
        outputs = [_both(ix.alg_v, (f.body_i, f.body_j))[:width] for f in members]
        split = len(key.pattern) - forces.n_value(key)
        chosen = [k for k, on in enumerate(key.pattern[:split]) if on]
        data = ca.DM(np.array([forces.data_of(f)[chosen] for f in members]).reshape(
            len(members), len(chosen)).T)
        values = ca.horzcat(*[forces.input_values(f, t, key.pattern[split:]) for f in members]) \
            if forces.n_value(key) else ca.DM(0, len(members))
        out.append(Group(kernel, np.array(inputs), np.array(outputs),
                         ca.vertcat(ca.repmat(t, 1, len(members)), data, _nonzeros(values))))
    return out


def _unrolled_force(ir: ModelIR, ix: Indices, force, t) -> Group:
    """An element without a kernel (equations.mapped.forces.unrolled, over every coordinate): its
    own
    kernel over the coordinates and velocities its -F depends on."""
    function = forces.unrolled(ir, force)
    tt, q, _ = function.sx_in()
    nb = ir.n_bodies
    v = ca.SX.sym("v", ix.n_v)
    if ix.form == "rp":
        q_dot, per_body = v, None
    else:
        per_body = [q[3 * nb + 4 * k:3 * nb + 4 * k + 4] for k in range(nb)]
        q_dot = ca.vertcat(v[:3 * nb], *[body.p_dot(p, v[3 * nb + 3 * k:3 * nb + 3 * k + 3])
                                          for k, p in enumerate(per_body)])
    generalized = function(tt, q, q_dot)[0]
    if per_body is not None:
        generalized = ca.vertcat(generalized[:3 * nb], *[
            body.moment(p, generalized[3 * nb + 4 * k:3 * nb + 4 * k + 4])
            for k, p in enumerate(per_body)])
    variables = ca.vertcat(q, v)
    columns = sorted(set(ca.jacobian(generalized, variables).sparsity().get_col()))
    rows = sorted(set(ca.sparsify(generalized).sparsity().row())) or [0]
    y = ca.SX.sym("y", len(columns))
    value = -generalized[rows]
    if columns:
        value = ca.substitute(value, variables[columns], y)
    kernel = ca.Function(f"element_{ix.form}_{function.name()}", [y, tt], [value],
                         ["y", "d"], ["out"])
    return Group(kernel, np.array([columns], dtype=int).reshape(1, len(columns)),
                 np.array([[ix.n_x + r for r in rows]]), t)


# --- the residual ---------------------------------------------------------------------------

def element_sum(ir: ModelIR, ix: Indices, t, constants: list) -> ElementSum:
    """constants: the row constants of p, [w, s] (, s_phi for ggl) (formulations.dae)."""
    groups = [*joint_groups(ir, ix, t, constants), *body_group(ir, ix, constants),
              *force_groups(ir, ix, t)]
    return ElementSum(ix.n_x + ix.n_z, ix.n_u, tuple(groups), ix.padding)


INTEGRATOR_IN = ["t", "x", "z", "p", "u"]  # casadi's DAE inputs (ca.dyn_in())


def oracles(ir: ModelIR) -> dict[str, dict[str, ca.Function]]:
    """Every DAE residual (both formulations, both stabilizations) with its daeF and jacF: the
    unrolled SX one where the model is small (UNROLLED_BODIES, UNROLLED_INSTRUCTIONS), else
    the element sum (oracle)."""
    sx = build_functions(ir).functions if len(ir.bodies) <= UNROLLED_BODIES else None
    out = {}
    for form in FORMULATIONS:
        for kind in KINDS:
            chosen = None if sx is None else from_residual(dae.residual(sx, form, kind))
            if chosen is not None and sum(chosen[f].n_instructions() for f in (
                    "daeF", "jacF")) > UNROLLED_INSTRUCTIONS:
                chosen = None
            out[name(form, kind)] = chosen or oracle(ir, form, kind)
    return out


def oracle(ir: ModelIR, form: str, kind: str) -> dict[str, ca.Function]:
    """dae_[ggl_]<form>, the DAE as IDAS integrates it, (t, x, z, p, u) -> (ode, alg, quad,
    zero), with `daeF` (its residual) and `jacF` (the Jacobian blocks d(ode, alg)/d(x, z)),
    the names casadi's IDAS interface looks up in the DAE's library."""
    if form not in FORMULATIONS:
        raise ValueError(f"unknown formulation {form}")
    ix = Indices(ir, form, kind)
    tau, x, z = ca.MX.sym("t"), ca.MX.sym("x", ix.n_x), ca.MX.sym("z", ix.n_z)
    p, u = ca.MX.sym("p", ix.n_p), ca.MX.sym("u", 0)
    elements = element_sum(ir, ix, p[0] + tau, ix.constants(p))
    unknowns = ca.vertcat(x, z)
    residual = elements.value(unknowns)
    ode, alg = residual[:ix.n_x], residual[ix.n_x:]
    xz = ((0, ix.n_x), (ix.n_x, ix.n_u))
    ode_x, ode_z, alg_x, alg_z = elements.jacobian(unknowns, xz, xz)
    ins = [tau, x, z, p, u]
    dae_name = name(form, kind)
    return {
        dae_name: ca.Function(dae_name, ins, [ode, alg, ca.MX(0, 1), ca.MX(0, 1)],
                              INTEGRATOR_IN, DYN_OUT),
        "daeF": ca.Function("daeF", ins, [ode, alg], INTEGRATOR_IN, ["ode", "alg"]),
        "jacF": ca.Function("jacF", ins, [ode_x, alg_x, ode_z, alg_z], INTEGRATOR_IN,
                            ["jac_ode_x", "jac_alg_x", "jac_ode_z", "jac_alg_z"]),
    }


DYN_OUT = ["ode", "alg", "quad", "zero"]  # casadi's DAE outputs (ca.dyn_out())


def jacobian_patterns(functions: dict[str, ca.Function]) -> dict[str, list[ca.Sparsity]]:
    """The Jacobian sparsity of the DAE function and of daeF, block by block (output-major:
    d output_i / d input_j), for jac_<name>_sparsity_out in the DAE's library: casadi's
    External reads a function's Jacobian pattern there and counts it dense without it, which
    makes IDAS's setup (Integrator::sp_jac_dae, from daeF) grow with the square of the model
    (docs/decisions/codegen-element-residuals.md). The (x, z) blocks are jacF's; the others
    come from CasADi's sparsity propagation through the function. The library holds no jac_<name>
    itself: AD through these functions stops with an error instead of using a pattern alone."""
    jac = functions["jacF"]
    known = {("ode", "x"): jac.sparsity_out(0), ("alg", "x"): jac.sparsity_out(1),
             ("ode", "z"): jac.sparsity_out(2), ("alg", "z"): jac.sparsity_out(3)}
    out = {}
    for function_name, function in functions.items():
        if function_name == "jacF":
            continue
        blocks = []
        for o in range(function.n_out()):
            for i in range(function.n_in()):
                block = (function.name_out(o), function.name_in(i))
                blocks.append(known[block] if block in known else function.jac_sparsity(o, i))
        out[function_name] = blocks
    return out


def from_residual(residual: ca.Function) -> dict[str, ca.Function]:
    """The same three functions for any residual (t, x, z, p) -> (ode, alg) (SX or MX), its
    Jacobian blocks by CasADi's AD of the whole residual (e.g. formulations.dae's unrolled SX)."""
    symbol = ca.SX if residual.is_a("SXFunction") else ca.MX
    ins = [symbol.sym(n, residual.sparsity_in(k)) for k, n in enumerate(residual.name_in())]
    ins.append(symbol.sym("u", 0))
    ode, alg = residual(*ins[:4])
    x, z = ins[1], ins[2]
    return {
        residual.name(): ca.Function(residual.name(), ins, [ode, alg, symbol(0, 1),
                                                            symbol(0, 1)],
                                     INTEGRATOR_IN, ["ode", "alg", "quad", "zero"]),
        "daeF": ca.Function("daeF", ins, [ode, alg], INTEGRATOR_IN, ["ode", "alg"]),
        "jacF": ca.Function("jacF", ins, [ca.jacobian(ode, x), ca.jacobian(alg, x),
                                          ca.jacobian(ode, z), ca.jacobian(alg, z)],
                            INTEGRATOR_IN, ["jac_ode_x", "jac_alg_x", "jac_ode_z", "jac_alg_z"]),
    }
