"""Constraint functions (phi, phi_q, nu, gamma) built from one kernel per kind of row, mapped
over its instances: code whose size and compile time do not grow with the number of joints.

A row of Phi depends only on its two bodies, so one SX kernel per (primitive kind, constant
vectors) gives phi, its Jacobian row (14 entries: r_i, p_i, r_j, p_j), nu and gamma of ONE row;
the kernel is mapped (MX) over every row of that kind, with the bodies' coordinates gathered by
index, and the Jacobian rows are scattered into Phi_q's pattern. Time enters through the
Taylor coefficients [f, f', f''] of each row's driving function at the instant, computed
outside the kernel, so nu and gamma are exact. The results equal the unrolled SX functions
(compiler.assemble) in value and sparsity; benchmarks/codegen_times.py --kernels measures them.

This covers the constraint family only; the mass matrix, forces and the r-omega functions are
still unrolled (compiler.functions).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.compiler import euler
from casmech.compiler.assemble import GROUND_POSE
from casmech.compiler.ir import GROUND_INDEX, ModelIR, PrimitiveIR
from casmech.compiler.primitives import PRIMITIVES, Frame

ROW = 14  # [r_i, p_i, r_j, p_j]


def row_kernels(kind: str, vectors: dict) -> tuple[ca.Function, ca.Function]:
    """(x[14], f[3]) -> (phi, jac[1x14], nu) and (x, x_dot, f) -> gamma for one row."""
    phi_of, _ = PRIMITIVES[kind]
    x, x_dot, coefficients = ca.SX.sym("x", ROW), ca.SX.sym("x_dot", ROW), ca.SX.sym("f", 3)
    tau = ca.SX.sym("tau")  # time from the instant: f(t + tau) to second order
    f = coefficients[0] + coefficients[1] * tau + coefficients[2] * tau**2 / 2
    frames = [Frame(x[0:3], euler.rotation(x[3:7])), Frame(x[7:10], euler.rotation(x[10:14]))]
    phi = phi_of(*frames, {k: ca.DM(v) for k, v in vectors.items()}, f)
    jac = ca.jacobian(phi, x)
    jac_x_dot = jac @ x_dot
    gamma = (-ca.jacobian(jac_x_dot, x) @ x_dot - 2 * ca.jacobian(jac_x_dot, tau)
             - ca.jacobian(ca.jacobian(phi, tau), tau))
    at = [ca.substitute(e, tau, 0) for e in (phi, jac, -ca.jacobian(phi, tau), gamma)]
    return (ca.Function(kind, [x, coefficients], at[:3], ["x", "f"], ["phi", "jac", "nu"]),
            ca.Function(f"{kind}_gamma", [x, x_dot, coefficients], at[3:],
                        ["x", "x_dot", "f"], ["gamma"]))


def normalization_kernels() -> tuple[ca.Function, ca.Function]:
    p, p_dot = ca.SX.sym("p", 4), ca.SX.sym("p_dot", 4)
    return (ca.Function("normalization", [p], [p.T @ p - 1, 2 * p.T, ca.SX(1, 1)]),
            ca.Function("normalization_gamma", [p, p_dot], [-2 * p_dot.T @ p_dot]))


def taylor(prim: PrimitiveIR, t):
    """[f, f', f''] of a row's driving function (with its offset) at t."""
    tt = ca.SX.sym("t")
    f = ca.SX(prim.f.casadi(t=tt) if prim.f is not None else 0.0) + prim.offset
    first = ca.jacobian(f, tt)
    taylor_of = ca.Function("f", [tt], [ca.vertcat(f, first, ca.jacobian(first, tt))])
    return taylor_of.call([t], True, False)[0]  # inlined: no call node (and code) per row


def _groups(ir: ModelIR) -> dict:
    """(kind, vectors) -> [(row, primitive)]: rows that share one kernel."""
    groups: dict = {}
    for row, prim in enumerate(ir.primitives):
        keys = PRIMITIVES[prim.kind][1]
        vectors = tuple((k, tuple(np.asarray(prim.vectors[k], float).ravel())) for k in keys)
        groups.setdefault((prim.kind, vectors), []).append((row, prim))
    return groups


class _Assembly:
    """Collects mapped outputs in kernel order and the Jacobian's (row, column, nonzero)."""

    def __init__(self, n_coordinates: int):
        self.n = n_coordinates
        self.parts: dict[str, list] = {"phi": [], "nu": [], "gamma": []}
        self.order: list[int] = []
        self.jac_blocks: list = []
        self.triplets: list[tuple[int, int, int]] = []  # row, column, index into jac nonzeros
        self.offset = 0

    def add(self, rows, columns, pattern, outputs, jac) -> None:
        """rows[k] uses coordinates columns[k] (ROW or 4 of them; >= n: ground)."""
        for name, value in zip(("phi", "nu", "gamma"), outputs, strict=True):
            self.parts[name].append(value.T)
        width = len(columns[0])
        for k, row in enumerate(rows):
            self.triplets += [(row, columns[k][c], self.offset + k * width + c) for c in pattern
                              if columns[k][c] < self.n]
        self.order += rows
        self.jac_blocks.append(ca.vec(jac))
        self.offset += width * len(rows)

    def result(self, n_rows: int) -> dict:
        inverse = [int(k) for k in np.argsort(self.order)]
        out = {name: ca.vertcat(*parts)[inverse] for name, parts in self.parts.items()}
        rows, cols, positions = zip(*self.triplets, strict=True) if self.triplets else ((), (), ())
        sparsity, mapping = ca.Sparsity.triplet(n_rows, self.n, list(rows), list(cols), True)
        take = [0] * len(mapping)
        for k, nonzero in enumerate(mapping):
            take[nonzero] = positions[k]
        values = ca.vertcat(*self.jac_blocks)[take] if take else ca.MX(0, 1)
        out["phi_q"] = ca.MX(sparsity, values)
        return out


def constraint_functions(ir: ModelIR) -> dict[str, ca.Function]:
    """phi, phi_q, nu, gamma as MX functions over mapped kernels (names and inputs as the
    interpreted bundle's)."""
    nb = ir.n_bodies
    n = 7 * nb
    t, q, q_dot = ca.MX.sym("t"), ca.MX.sym("q", n), ca.MX.sym("q_dot", n)
    padded, padded_dot = ca.vertcat(q, ca.DM(GROUND_POSE)), ca.vertcat(q_dot, ca.DM.zeros(7))

    def index(k: int) -> list[int]:
        if k == GROUND_INDEX:
            return list(range(n, n + 7))
        return [3 * k + i for i in range(3)] + [3 * nb + 4 * k + i for i in range(4)]

    assembly = _Assembly(n)
    for (kind, vectors), members in _groups(ir).items():
        kernel, kernel_gamma = row_kernels(kind, dict(vectors))
        columns = [index(p.body_i) + index(p.body_j) for _, p in members]
        flat = [c for cs in columns for c in cs]
        x = ca.reshape(padded[flat], ROW, len(members))
        x_dot = ca.reshape(padded_dot[flat], ROW, len(members))
        coefficients = ca.horzcat(*[taylor(p, t) for _, p in members])
        phi, jac, nu = kernel.map(len(members), "serial")(x, coefficients)
        gamma = kernel_gamma.map(len(members), "serial")(x, x_dot, coefficients)
        pattern = [c for c in range(ROW) if kernel.sparsity_out(1).has_nz(0, c)]
        assembly.add([row for row, _ in members], columns, pattern, (phi, nu, gamma), jac)
    if nb:
        norm, norm_gamma = normalization_kernels()
        p, p_dot = ca.reshape(q[3 * nb:], 4, nb), ca.reshape(q_dot[3 * nb:], 4, nb)
        phi, jac, nu = norm.map(nb, "serial")(p)
        rows = list(range(len(ir.primitives), len(ir.primitives) + nb))
        assembly.add(rows, [index(k)[3:] for k in range(nb)], range(4),
                     (phi, nu, norm_gamma.map(nb, "serial")(p, p_dot)), jac)
    out = assembly.result(len(ir.primitives) + nb)
    return {
        "phi": ca.Function("phi", [t, q], [out["phi"]], ["t", "q"], ["phi"]),
        "phi_q": ca.Function("phi_q", [t, q], [out["phi_q"]], ["t", "q"], ["phi_q"]),
        "nu": ca.Function("nu", [t, q], [out["nu"]], ["t", "q"], ["nu"]),
        "gamma": ca.Function("gamma", [t, q, q_dot], [out["gamma"]], ["t", "q", "q_dot"],
                             ["gamma"]),
    }
