"""Singular poses a mechanism with loops passed during a dynamics run, by joint and YAML line.

At a singular pose the constraint Jacobian Phi_q loses rank: rows that were independent at t0
become dependent (a four-bar's flat pose). After a run, the rows of Phi_q independent at the
first output row (checks.structure), each scaled to unit length, are evaluated at every output
row by one mapped call; where the determinant of their Gram matrix falls below
singular_pose_ratio (core.options.DynamicsSolver) times its value at t0 (one singular value of
the unit rows shrinking ~1/sqrt(that ratio) times), the run passed
near a singular pose. Each such stretch of rows is reported once, at its smallest
determinant: the time, the smallest singular value of the unit rows there, and the joints whose
rows make up the dependency (its singular vector), each with its file:line:col.

The log-determinants: for a bundle loaded from the compiled-model cache, of up to COMPILED_ROWS
rows, by one compiled function of (t, q) over the rows in the rows' C loop (logdet_function:
Phi_q of the bundle's IR inline, the Gram matrix and CasADi's sparse LDL factor; runtime.
joint_rows.over_rows, CasADi's map where the loop cannot run it), cached under the bundle's
library key and the rows, so built once per machine; otherwise, and at a row where the compiled
value is not finite (a Gram matrix not numerically positive definite), in NumPy from Phi_q's
dense rows (their Gram matrices, each scaled to a unit diagonal, by Cholesky factors).

A tree has no loop to close (its joints' rows are independent at every pose) and is not
examined; nor is a run above MAX_ENTRIES (output rows x rows of Phi x coordinates: the dense
Jacobians held at once: a memory bound). The ratio's measurements:
docs/decisions/singular-poses.md; the compiled log-determinant's:
docs/decisions/loop-dae-loose-tolerance.md.
"""

from __future__ import annotations

import warnings

import casadi as ca
import numpy as np

from casmech.core.options import DynamicsSolver
from casmech.equations.checks import structure, worst_joints
from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError, UsageError
from casmech.runtime.buffers import ColumnCall
from casmech.runtime.nonfinite import all_finite
from casmech.runtime.results import Result
from casmech.runtime.row_calls import over_rows, rows_of
from casmech.runtime.workspace import Workspace, of

DEFAULT = DynamicsSolver()  # the defaults (core.options)
MAX_ENTRIES = 20_000_000  # output rows x rows of Phi x coordinates examined at most
# rows of Phi whose log-determinant is compiled at most (the LDL factor's code, and gcc's time,
# grow with them)
COMPILED_ROWS = 60


def _entries(functions: SystemFunctions, workspace: Workspace | None) -> dict:
    """The check's entries for the bundle (kept in the workspace): "jacobians", Phi_q's mapped
    call; "compiled", (the rows examined, the compiled log-determinant's mapped call or None)
    of the last rows examined; "shape", Phi_q's (rows, coordinates)."""
    return of(functions, workspace).one("singular_pose_jacobian", dict)


def _jacobians(functions: SystemFunctions, workspace: Workspace | None) -> ColumnCall:
    """Phi_q, dense, at output rows by mapped calls."""
    def build() -> ColumnCall:
        phi_q = functions["phi_q"]
        t, q = ca.MX.sym("t"), ca.MX.sym("q", phi_q.size1_in(1))
        return ColumnCall(ca.Function("phi_q_dense", [t, q], [ca.densify(phi_q(t, q))]))

    entries = _entries(functions, workspace)
    if "jacobians" not in entries:
        entries["jacobians"] = build()
    return entries["jacobians"]


def logdet_function(phi_q: ca.Function, rows) -> ca.Function:
    """(t, q, and phi_q's further inputs) -> log det of the Gram matrix of the rows `rows` of
    phi_q (an SX Function) each scaled to unit length: the Gram matrix G (each product once)
    factored by CasADi's sparse LDL (G[p, p] = (I + L) D (I + L)^T, p its fill-reducing
    order), and log prod_k D_k / G[p_k, p_k] (each factor in (0, 1] where G is positive
    definite); not finite where G is not numerically positive definite. Its inputs are named
    as phi_q's but q, which is `x`: the input a compiled function's C entry point takes its
    rows' states by (backends.rk_library.Entry), so that the rows' C loop runs it."""
    inputs = phi_q.sx_in()
    jacobian = phi_q(*inputs)[list(rows), :]
    gram = ca.mtimes(jacobian, jacobian.T)
    gram = ca.tril(gram) + ca.tril(gram, False).T
    pivots, _, order = ca.ldl(gram)
    ratio = ca.SX(1)
    for k, j in enumerate(order):
        ratio = ratio * (pivots[k] / gram[j, j])
    names = ["x" if name == "q" else name for name in phi_q.name_in()]
    return ca.Function("unit_gram_logdet", inputs, [ca.log(ratio)], names, ["logdet"])


class _Compiled:
    """logdet_function compiled, over output rows (with a parametric library's model data as
    its last input) in the rows' C loop (runtime.joint_rows.over_rows), or casadi's map."""

    def __init__(self, function: ca.Function, data: np.ndarray | None):
        self.call = over_rows(function)
        self.data = () if data is None else (np.asarray(data, float),)

    def __call__(self, times: np.ndarray, q: np.ndarray) -> np.ndarray:
        return rows_of(self.call, times, q, *self.data)[0].ravel()


def _compiled(functions: SystemFunctions, rows: list[int],
              workspace: Workspace | None) -> _Compiled | None:
    """logdet_function compiled for a bundle loaded from the compiled-model cache
    (backends.library.compile_keyed, under the bundle's library key, or a parametric
    library's, and the rows; Phi_q of the bundle's IR, or of the parametric library's
    symbolic IR), for up to COMPILED_ROWS rows examined; None otherwise, without a C compiler,
    or when the build failed (with a warning)."""
    entries = _entries(functions, workspace)
    key = tuple(rows)
    if entries.get("compiled", (None,))[0] != key:
        entries["compiled"] = key, None
        if functions.mode == "compiled" and len(rows) <= COMPILED_ROWS:
            entries["compiled"] = key, _build(functions, rows)
    return entries["compiled"][1]


def _build(functions: SystemFunctions, rows: list[int]) -> _Compiled | None:
    """_compiled's library, found or built (None: no cached library to key it by, no C
    compiler, or a failed build)."""
    from casmech.backends import build
    from casmech.backends.library import compile_keyed
    from casmech.equations.functions import build_functions
    from casmech.model import parametric

    library, data = functions.parametric, functions.data
    if library is not None and data is not None:
        bundle = {"parametric": library.folder.name, "signature": library.signature}

        def phi_q() -> ca.Function:
            split = parametric.split(functions.ir)
            return build_functions(split.ir, split.symbols)["phi_q"]
    elif functions.library_key is not None and data is None and library is None:
        bundle = {"bundle": functions.library_key}

        def phi_q() -> ca.Function:
            return build_functions(functions.ir)["phi_q"]
    else:
        return None
    toolchain = build.Toolchain()
    if not build.available(toolchain):
        return None
    try:
        # "x": the function's q input is named x (logdet_function); libraries built when it
        # was named q (which the rows' C loop cannot run) are not this key's
        compiled = compile_keyed({"kind": "unit gram logdet", **bundle, "rows": rows,
                                  "state": "x"}, lambda: (
            {"unit_gram_logdet": logdet_function(phi_q(), rows)}, {}, toolchain),
            toolchain=toolchain)
    except (AnalysisError, UsageError) as error:
        warnings.warn(f"{str(error).splitlines()[0]}; the singular-pose check runs in NumPy",
                      stacklevel=2)
        return None
    return _Compiled(compiled["unit_gram_logdet"], data)


def unit_gram_logdet(functions: SystemFunctions, times, q, rows,
                     workspace: Workspace | None = None) -> np.ndarray:
    """log det(J J^T) of the rows `rows` of Phi_q scaled to unit length, at each (t, q): by
    the compiled function where there is one (_compiled) and its value is finite, else from
    the rows' Gram matrix scaled by its diagonal, by a Cholesky factor (slogdet where one is
    not numerically positive definite)."""
    times, q = np.asarray(times, float), np.asarray(q, float)
    compiled = _compiled(functions, list(map(int, rows)), workspace)
    if compiled is None:
        return _dense_logdet(functions, times, q, rows, workspace)
    logdet = compiled(times, q)
    if not all_finite(logdet):
        failed = ~np.isfinite(logdet)
        logdet[failed] = _dense_logdet(functions, times[failed], q[failed], rows, workspace)
    return logdet


def _dense_logdet(functions: SystemFunctions, times: np.ndarray, q: np.ndarray, rows,
                  workspace: Workspace | None) -> np.ndarray:
    """unit_gram_logdet in NumPy from Phi_q's dense rows."""
    n = len(times)
    m, columns = functions["phi_q"].size_out(0)
    flat, = _jacobians(functions, workspace)(times[None, :], q.T)
    jacobian = flat.reshape(m, n, columns).transpose(1, 0, 2)
    if len(rows) < m:
        jacobian = jacobian[:, rows, :]
    gram = jacobian @ jacobian.transpose(0, 2, 1)
    scale = 1.0 / np.sqrt(np.diagonal(gram, axis1=1, axis2=2))
    gram = gram * scale[:, :, None] * scale[:, None, :]
    try:
        factor = np.linalg.cholesky(gram)
    except np.linalg.LinAlgError:
        return np.linalg.slogdet(gram)[1]
    with np.errstate(divide="ignore"):
        return 2.0 * np.sum(np.log(np.diagonal(factor, axis1=1, axis2=2)), axis=1)


def examinable(functions: SystemFunctions, rows: int,
               workspace: Workspace | None = None) -> bool:
    """Whether a run of `rows` output rows is examined (MAX_ENTRIES); Phi_q's shape read once
    per workspace (the check's entries)."""
    entries = _entries(functions, workspace)
    shape = entries.get("shape")
    if shape is None:
        shape = entries["shape"] = functions["phi_q"].size_out(0)
    return rows * shape[0] * shape[1] <= MAX_ENTRIES


def singular_poses(functions: SystemFunctions, result: Result, loops: bool,
                   settings: DynamicsSolver = DEFAULT,
                   workspace: Workspace | None = None) -> list[dict] | None:
    """The singular poses the run passed near (module docstring); None when not examined."""
    if not loops:
        return None
    times, q = result.t, result.q
    if len(times) < 2 or not examinable(functions, len(times), workspace):
        return None
    limits = settings.assembly.linear_algebra
    rows = _independent(functions, result, float(times[0]), q[0], limits)
    drop = unit_gram_logdet(functions, times, q, rows, workspace)
    near = drop - drop[0] < np.log(settings.singular_pose_ratio)
    return [_pose(functions, float(times[k]), q[k], rows) for k in _deepest(near, drop)]


def _independent(functions: SystemFunctions, result: Result, t: float, q,
                 limits) -> list[int]:
    """The rows of Phi independent at the first row: every row when the run dropped none (its
    own check at t0: runtime.dynamics for r-p / r-omega; for joint coordinates, the cut rows
    independent on the tree's motions, with which the tree joints' own rows are independent
    too), else checks.structure's."""
    meta = result.metadata
    if meta.get("formulation") in ("rp", "romega", "joint") and meta.get("dropped_rows") == 0:
        return list(range(functions.n_rows))
    return list(structure(functions, t, q, limits).independent)


def _deepest(near: np.ndarray, drop: np.ndarray) -> list[int]:
    """The row of smallest determinant in each stretch of consecutive near rows."""
    if not near.any():
        return []
    edges = np.flatnonzero(np.diff(np.concatenate([[0], near.astype(int), [0]])))
    return [start + int(np.argmin(drop[start:stop])) for start, stop in edges.reshape(-1, 2)]


def _pose(functions: SystemFunctions, t: float, q: np.ndarray, rows: list[int]) -> dict:
    """The pose at a row: the smallest singular value of the unit kept rows, and the joints
    weighted by its left singular vector (the dependency among their rows)."""
    phi_q = np.array(ca.DM(functions["phi_q"](t, q)))
    unit = phi_q[rows] / np.linalg.norm(phi_q[rows], axis=1, keepdims=True)
    u, s, _ = np.linalg.svd(unit)
    weights = np.zeros(len(phi_q))
    weights[rows] = np.abs(u[:, s.size - 1])
    joints = worst_joints(functions, weights)
    return {"t": t, "smallest_singular_value": float(s[-1]),
            "joints": [str(name) for name, _, _ in joints],
            "sources": [str(source) if source else "" for _, source, _ in joints]}


def describe(pose: dict) -> str:
    """One line for the command line."""
    joints = ", ".join(f"{name} ({source})" if source else name
                       for name, source in zip(pose["joints"], pose["sources"], strict=True))
    return (f"near a singular pose at t = {pose['t']:.6g} (smallest singular value "
            f"{pose['smallest_singular_value']:.2e} of the unit constraint rows): {joints}")
