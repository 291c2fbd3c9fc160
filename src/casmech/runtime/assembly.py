"""Assembly: positions from the file's pose, then velocities and accelerations.

The assembled pose is the point of Phi(t, q) = 0 closest to the file's pose (Euclidean in q):
the root of numerics.kkt.closest_point's KKT system, reached in two stages. First the
least-squares Newton of `newton` gets onto the right branch: drivers of composite joints are
reached by continuation, their values scaled from 0 (the pose in the file) to 1 in steps of at
most max_driver_step radians/metres (core.options.Assembly, the settings of every function
here), so Newton never jumps to the mirrored root of a rotation driver. Its end point depends
on Newton's path where the mechanism has degrees of freedom (within O(distance^2) of the
closest point); the rootfinder then converges to the closest point
in a few iterations. casmech.optimal differentiates the same rootfinder.

Accelerations and multipliers are numerics.kkt.saddle's, the projection back onto the
constraints formulations.augmented.projection's: the Functions casmech.optimal and the integrators
use. The least-squares steps (Newton, velocities) run on the bundle's sparse matrices
(CasADi DM) by numerics.numeric_qr (numpy.linalg.lstsq's answer, dense below its size limits),
so nothing is dense in the number of bodies; only the per-row kinematics code
(solve_kinematic_accelerations, solve_multipliers: kinematics uses it for the rows its mapped
step rejects) stays dense. The Functions built here are kept in the run's workspace
(runtime.workspace; by default the bundle's).
"""

from __future__ import annotations

import math
from dataclasses import field

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.core.options import Assembly, Fallback
from casmech.core.records import record
from casmech.equations.checks import dependent_joints, structure, worst_joints
from casmech.equations.functions import SystemFunctions
from casmech.errors import AnalysisError, FailureContext
from casmech.runtime import cancel, initial_holds
from casmech.runtime.nonfinite import NonFinite
from casmech.runtime.workspace import Workspace, of

DEFAULT, FALLBACK = Assembly(), Fallback()  # the defaults (core.options)
MAX_CONTINUATION = 1000  # steps of driver continuation at most: a bounded time to fail


def initial_guess(functions: SystemFunctions) -> np.ndarray:
    bodies = functions.ir.bodies
    return np.concatenate([b.r0 for b in bodies] + [b.p0 for b in bodies] + [np.zeros(0)])


def file_velocities(functions: SystemFunctions, q: np.ndarray) -> np.ndarray:
    """q_dot from the file's global velocities: p_dot = 1/2 E(p)^T omega."""
    bodies = functions.ir.bodies
    if not bodies:
        return np.zeros(0)
    nb = len(bodies)
    e = euler.numeric_columns(euler.e_matrix, q[3 * nb:].reshape(nb, 4).T)  # 3 x 4 nb
    omega = np.array([b.omega0 for b in bodies])  # nb x 3
    p_dot = 0.5 * np.einsum("ikj,ki->kj", e.reshape(3, nb, 4), omega)
    return np.concatenate([np.concatenate([b.r_dot0 for b in bodies]), p_dot.ravel()])


@record(frozen=False)
class UnmetRows(FailureContext):
    """A failure naming constraint rows (RowInfo, residual), worst first: the constraints that
    cannot be met (`casmech check` reports each as an E502)."""

    rows: list = field(default_factory=list)

    def format(self) -> str:
        at = f"at t = {self.time:.6g}: " if self.time is not None else ""
        lines = [f"analysis failed {at}{self.cause}"]
        for row, residual in self.rows:
            where = f"{row.source}: " if row.source else ""
            lines.append(f"  {where}{row_text(row)} (residual {residual:.3e})")
        return "\n".join(lines)


def row_text(row) -> str:
    """"joint 'tether': |d_ij|^2 = length^2" or "body 'rod2': p^T p - 1" (a RowInfo)."""
    if row.kind == "normalization":
        return f"body '{row.joint}': p^T p - 1"
    return f"joint '{row.joint}': {row.label.split(': ', 1)[-1]}"


def unmet_rows(functions: SystemFunctions, start: np.ndarray, best: np.ndarray,
               tolerance: float, count: int = 3) -> list:
    """(RowInfo, residual at the best iterate) of the rows Newton left unmet from its start to
    its best iterate: the worst row of each of the `count` joints (or bodies' normalization)
    with the largest residuals, worst first. A row Newton met on the way is no culprit, and one
    it broke on the way (diverging) was met at the start; when no row is unmet at both, those
    unmet at the best iterate."""
    start, best = np.abs(np.ravel(start)), np.abs(np.ravel(best))
    unmet = (start > tolerance) & (best > tolerance)
    unmet = unmet if unmet.any() else best > tolerance
    worst: dict[str, tuple[object, float]] = {}
    for row, value, chosen in zip(functions.rows, best, unmet, strict=True):
        if chosen and value > worst.get(row.joint, (None, -1.0))[1]:
            worst[row.joint] = (row, float(value))
    return sorted(worst.values(), key=lambda item: -item[1])[:count]


def newton(functions: SystemFunctions, t: float, q: np.ndarray, scale: float | None = None,
           tolerance: float | None = None, settings: Assembly = DEFAULT) -> np.ndarray:
    """Solve Phi(t, q) = 0 by Newton with least-squares steps (redundant rows allowed), to
    `tolerance` (default settings.tolerance). When it does not converge, the error names the
    rows it left unmet (unmet_rows): the constraints that cannot be met together (a length no
    pose reaches)."""
    tolerance = settings.tolerance if tolerance is None else tolerance
    q = np.array(q, float)
    start = best_phi = None
    for _ in range(settings.max_iterations):
        cancel.poll()
        phi, phi_q = _evaluate(functions, t, q, scale)
        finite(t, "phi", phi, q)
        if _worst(phi) <= tolerance:
            return q
        start = phi if start is None else start
        best_phi = phi if best_phi is None or _worst(phi) < _worst(best_phi) else best_phi
        from casmech.numerics import numeric_qr  # (where Phi is not met yet)

        q += numeric_qr.lstsq(phi_q, -phi, limits=settings.linear_algebra)
    phi, phi_q = _evaluate(functions, t, q, scale)
    if _worst(phi) <= 1e3 * tolerance:
        return q
    best_phi = phi if _worst(phi) < _worst(best_phi) else best_phi
    cause = (f"the constraints cannot be met: positions did not converge (max |Phi| = "
             f"{_worst(best_phi):.3e} at best in {settings.max_iterations} Newton iterations); "
             "the rows left unmet:")
    raise AnalysisError(UnmetRows(t, cause, worst_joints(functions, best_phi),
                                  rows=unmet_rows(functions, start, best_phi, tolerance)))


def finite(t: float, name: str, values: np.ndarray, q: np.ndarray, q_dot=None) -> None:
    """NonFinite (runtime.nonfinite) when `values` (a constraint vector at (q, q_dot)) are not
    all finite: no least squares is taken of them. (Accelerations and multipliers of forces
    or a gamma that are not finite come out NaN instead: the Result they go to says which
    column.)"""
    if not np.all(np.isfinite(values)):
        q_dot = np.zeros_like(q) if q_dot is None else q_dot
        raise NonFinite(t, name, values, (q, q_dot))


def _evaluate(functions, t, q, scale):
    """(phi as a flat array, phi_q as a sparse DM)."""
    if scale is None:
        return functions.vector("phi", t, q), functions["phi_q"](t, q)
    phi, phi_q = functions["phi_scaled"](t, q, scale)
    return np.array(phi).ravel(), phi_q


def _far_drivers(functions: SystemFunctions, t: float, reach: float) -> list:
    """(joint, source, |f(t)|) of the drivers beyond the continuation's reach, farthest
    first."""
    far = [(p.row.joint, p.row.source, abs(p.f.value(t=t))) for p in functions.ir.primitives
           if p.is_driver and p.f and not abs(p.f.value(t=t)) <= reach]
    return sorted(far, key=lambda item: -item[2] if math.isfinite(item[2]) else -math.inf)


def driver_span(functions: SystemFunctions, t: float) -> float:
    """Largest |f(t)| over the composite-joint drivers (how far continuation must go)."""
    values = [abs(p.f.value(t=t)) for p in functions.ir.primitives if p.is_driver and p.f]
    return max(values, default=0.0)


def assemble_positions(functions: SystemFunctions, t: float = 0.0, q=None,
                       settings: Assembly = DEFAULT,
                       workspace: Workspace | None = None) -> np.ndarray:
    """The point of Phi(t, .) = 0 closest to q (default: the file's pose, where the joints'
    `initial:` values placed the bodies, holding those values: _held_positions); q itself
    when it meets the constraints (module docstring)."""
    held = initial_holds.holds(functions, workspace) if q is None else None
    if held is not None:
        return _held_positions(held, t, initial_guess(functions), settings)
    reference = initial_guess(functions) if q is None else np.array(q, float)
    if _worst(functions.vector("phi", t, reference)) <= settings.tolerance:
        return reference
    return closest_point(functions, t, least_squares_positions(functions, t, reference,
                                                               settings),
                         reference, settings, workspace)


def _held_positions(held: initial_holds.Holds, t: float, posed: np.ndarray,
                    settings: Assembly) -> np.ndarray:
    """With the joints' initial values held (runtime/initial_holds.py): `posed` when it meets
    them and the constraints (a tree), else continuation from the file's pose to the values
    and the drivers together, then the closest point to `posed`. E504 for a value the others
    fix already, E503 when the loops do not close with them."""
    bundle = held.positions
    held.check_independent(bundle, t, held.reference, "coordinate")
    if _worst(bundle.vector("phi", t, posed)) <= settings.tolerance:
        return posed
    try:
        q = least_squares_positions(bundle, t, held.reference, settings, held.span)
    except AnalysisError as error:
        raise held.unmet(error) from None
    return closest_point(bundle, t, q, posed, settings)


def least_squares_positions(functions: SystemFunctions, t: float, q: np.ndarray,
                            settings: Assembly = DEFAULT, span: float = 0.0) -> np.ndarray:
    """Driver continuation (and, `span` > 0, of held initial values that far), then Newton
    with least-squares steps, from q."""
    span = max(driver_span(functions, t), span)
    farthest = settings.max_driver_step * MAX_CONTINUATION
    if not span <= farthest:  # (NaN included)
        raise AnalysisError(FailureContext(
            t, f"a driver's value is {span:.3g} (rad or m) away from the pose in the file, "
               f"farther than assembly follows drivers (at most {farthest:g}); write the pose "
               "nearer the drivers' values at the start", _far_drivers(functions, t, farthest),
               "|f(t)|"))
    steps = max(1, math.ceil(span / settings.max_driver_step))
    for k in range(1, steps + 1):  # the last step is at scale 1: phi itself
        q = newton(functions, t, q, scale=k / steps, settings=settings,
                   tolerance=settings.continuation_tolerance if k < steps else None)
    return q


def closest_point(functions: SystemFunctions, t: float, q: np.ndarray,
                  reference: np.ndarray, settings: Assembly = DEFAULT,
                  workspace: Workspace | None = None) -> np.ndarray:
    """numerics.kkt.closest_point from q (on Phi = 0) over the rows independent at q; q
    itself where those rows fix every coordinate (no degree of freedom: an isolated root, the
    closest point of its neighbourhood) or where the rootfinder does not reach
    |Phi| <= settings.tolerance (a Jacobian losing rank at q makes the KKT matrix nearly
    singular)."""
    from casmech.numerics import kkt

    rows = structure(functions, t, q, settings.linear_algebra).independent
    if len(rows) == functions.n_coordinates:
        return q
    key = (rows, settings.root_tolerance, settings.root_iterations)
    solve = of(functions, workspace).kept("closest_point", key, lambda: kkt.closest_point(
        functions["phi"], functions["phi_q"], rows, settings=settings))
    polished = np.array(solve(q, t, reference)[0]).ravel()
    worst = _worst(functions.vector("phi", t, polished))
    return polished if worst <= settings.tolerance else q


def _worst(phi: np.ndarray) -> float:
    """max |phi| (inf when not finite)."""
    worst = np.max(np.abs(phi), initial=0.0)
    return worst if np.isfinite(worst) else math.inf


def initial_state(functions: SystemFunctions, t0: float = 0.0, settings: Assembly = DEFAULT,
                  workspace: Workspace | None = None):
    """Assembled positions and the file's velocities projected onto the constraints (with
    the joints' `initial:` rates held: E504 for a rate the others fix already)."""
    q = assemble_positions(functions, t0, settings=settings, workspace=workspace)
    held = initial_holds.holds(functions, workspace)
    if held is None:
        return q, solve_velocities(functions, t0, q, file_velocities(functions, q), settings)
    held.check_independent(held.velocities, t0, q, "rate")
    return q, solve_velocities(held.velocities, t0, q, file_velocities(functions, q), settings)


def solve_velocities(functions: SystemFunctions, t: float, q: np.ndarray,
                     q_dot_guess: np.ndarray, settings: Assembly = DEFAULT) -> np.ndarray:
    """Phi_q q_dot = nu, closest (least squares) to the guess (the guess itself when it is
    zero and nu is structurally zero: no drivers, a mechanism starting from rest)."""
    if not np.any(q_dot_guess) and not functions["nu"].sparsity_out(0).nnz():
        return np.array(q_dot_guess, float)
    from casmech.numerics import numeric_qr

    phi_q = functions["phi_q"](t, q)
    nu = functions.vector("nu", t, q)
    finite(t, "nu", nu, q)
    residual = nu - np.array(ca.mtimes(phi_q, ca.DM(q_dot_guess))).ravel()
    return q_dot_guess + numeric_qr.lstsq(phi_q, residual, limits=settings.linear_algebra)


def solve_kinematic_accelerations(functions: SystemFunctions, t: float, q: np.ndarray,
                                  q_dot: np.ndarray, settings: Assembly = DEFAULT) -> np.ndarray:
    """Phi_q q_ddot = gamma, for a fully driven (0-DOF) mechanism."""
    phi_q = functions.matrix("phi_q", t, q)
    gamma = functions.vector("gamma", t, q, q_dot)
    if not np.all(np.isfinite(gamma)):  # no least squares of it: the row says (Result)
        return np.full(functions.n_coordinates, np.nan)
    q_ddot, _, rank, _ = np.linalg.lstsq(phi_q, gamma, rcond=None)
    if rank < functions.n_coordinates:
        cause = ("singular configuration: the constraint Jacobian lost rank "
                 f"({rank} < {functions.n_coordinates}); the joints involved:")
        raise AnalysisError(FailureContext(t, cause, dependent_joints(
            functions, phi_q, limits=settings.linear_algebra), "weight in the dependency"))
    return q_ddot


def solve_multipliers(functions: SystemFunctions, t: float, q: np.ndarray, q_dot: np.ndarray,
                      q_ddot: np.ndarray) -> np.ndarray:
    """Inverse dynamics: Phi_q^T lam = Q - M q_ddot (minimum norm where rows are redundant)."""
    mass = functions.matrix("mass_matrix", q)
    forces = functions.vector("generalized_forces", t, q, q_dot)
    if not (np.all(np.isfinite(forces)) and np.all(np.isfinite(q_ddot))):
        return np.full(functions.n_rows, np.nan)  # no least squares of them (as above)
    phi_q = functions.matrix("phi_q", t, q)
    return np.linalg.lstsq(phi_q.T, forces - mass @ q_ddot, rcond=None)[0]


def solve_dynamic_accelerations(functions: SystemFunctions, t: float, q: np.ndarray,
                                q_dot: np.ndarray, rows=None, settings: Assembly = DEFAULT,
                                workspace: Workspace | None = None
                                ) -> tuple[np.ndarray, np.ndarray]:
    """[M Phi_q^T; Phi_q 0] [q_ddot; lam] = [Q; gamma]: the motion the forces produce now, by
    numerics.kkt.saddle over the rows independent at q (checks.structure; the normalization
    rows and every joint row of a mechanism without redundant joints). lam covers every row:
    on redundant rows, the multipliers of least norm with the same reaction (what least
    squares of the whole singular system gives). `rows` restricts the constraints to an
    independent subset instead (lam then has their length)."""
    from casmech.numerics import kkt
    from casmech.runtime.dae_rows import minimum_norm

    if rows is None:
        independent = list(structure(functions, t, q, settings.linear_algebra).independent)
        q_ddot, lam = solve_dynamic_accelerations(functions, t, q, q_dot, independent,
                                                  settings, workspace)
        if len(independent) == functions.n_rows:
            return q_ddot, lam
        phi_q = functions["phi_q"](t, q)
        full = np.zeros(functions.n_rows)
        full[independent] = lam
        return q_ddot, np.array(minimum_norm(phi_q, ca.DM(full), independent)).ravel()
    rows = list(rows)
    phi_q = functions["phi_q"](t, q)[rows, :]
    mass = functions["mass_matrix"](q)
    saddle = of(functions, workspace).kept(  # the rows fix the patterns
        "saddle", tuple(rows), lambda: kkt.saddle(mass.sparsity(), phi_q.sparsity()))
    forces = functions["generalized_forces"](t, q, q_dot)
    gamma = functions.vector("gamma", t, q, q_dot)
    if not (np.all(np.isfinite(np.array(forces))) and np.all(np.isfinite(gamma))):
        return np.full(functions.n_coordinates, np.nan), np.full(len(rows), np.nan)
    return saddle_solution(saddle, mass, phi_q, forces, gamma[rows], np.zeros(len(rows)))


def saddle_solution(saddle: ca.Function, mass: ca.DM, jac: ca.DM, forces, gamma: np.ndarray,
                    w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(v_dot, lam) by a numerics.kkt.saddle Function; where its LU meets a zero pivot (P lost
    rank exactly and no row is masked), the least-squares solution."""
    try:
        v_dot, lam = (np.array(out).ravel() for out in saddle(mass, jac, forces, gamma, w))
        if np.all(np.isfinite(v_dot)) and np.all(np.isfinite(lam)):
            return v_dot, lam
    except RuntimeError as error:
        cancel.check(error)
    lhs = np.block([[np.array(mass), np.array(jac).T], [np.array(jac), -np.diag(w)]])
    z = np.linalg.lstsq(lhs, np.concatenate([np.ravel(np.array(forces)), gamma]), rcond=None)[0]
    return z[:mass.size1()], z[mass.size1():]


def project(functions: SystemFunctions, form, t: float, q: np.ndarray, v: np.ndarray,
            penalty: float, accept: float | None = None, settings: Assembly = DEFAULT,
            fallback: Fallback = FALLBACK, workspace: Workspace | None = None
            ) -> tuple[np.ndarray, np.ndarray]:
    """Back onto Phi = 0, then onto the velocity constraints: formulations.augmented.projection
    (mass-orthogonal Gauss-Newton steps damped with the augmented-Lagrangian penalty,
    fallback.projection_iterations per call) called until |Phi| <= settings.tolerance. Near a
    singular configuration the damping keeps a step from jumping along the nearly lost
    direction (a Euclidean least-squares step there moved A02 onto the wrong branch), at the
    price of slow progress along it: a residual below `accept` (default the tolerance) after
    settings.max_iterations steps is taken as converged."""
    from casmech.formulations import augmented
    from casmech.formulations.table import BODY_FORMS

    accept = settings.tolerance if accept is None else accept
    name = next(key for key, value in BODY_FORMS.items() if value == form)
    per_call = fallback.projection_iterations
    step = of(functions, workspace).kept("projection", (name, per_call), lambda: (
        augmented.projection(functions.functions, name, fallback)))
    for _ in range(math.ceil(settings.max_iterations / per_call)):
        q, v = (np.array(out).ravel() for out in step(t, q, v, penalty))
        phi = functions.vector("phi", t, q)
        if _worst(phi) <= settings.tolerance:
            return q, v
    if _worst(phi) > accept:
        cause = (f"the projection onto the constraints did not converge in "
                 f"{settings.max_iterations} iterations (max |Phi| = {np.max(np.abs(phi)):.3e}); "
                 "the joints with the largest residuals:")
        raise AnalysisError(FailureContext(t, cause, worst_joints(functions, phi)))
    return q, v
