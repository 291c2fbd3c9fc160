"""Statics: the equilibrium pose under gravity, springs, bushings, constant forces and motors
held at their drivers (at t = 0).

Equations (r-p form, Euler-parameter normalization rows part of Phi): Phi(q) = 0 and
Q(q, 0) - Phi_q^T lam = 0, the equations of motion with q_dot = q_ddot = 0 (the sign
convention of inverse dynamics, so the multipliers give the usual joint reactions).

Solver: pseudo-transient continuation (implicit damped dynamic relaxation) on the constraint
manifold, which becomes Newton's method near the solution. Every iterate is on Phi = 0
(assembly's Newton projects it back); lam is a least-squares multiplier there, so the force
residual R = Q - Phi_q^T lam is the unbalanced generalized force N N^T Q, N an orthonormal
basis of the null space of Phi_q from a column-pivoted QR of Phi_q^T (reduced_system). In those
independent coordinates z (dq = N dz) a step solves

    (K + mu M) dz = f,   f = N^T Q,  K = -N^T dR/dq N,  M = N^T M_q N

(K the tangent stiffness by AD, lam fixed: the constraint-curvature term; M the mass matrix).
That is backward Euler on the overdamped flow M z' = f with pseudo time step 1/mu: far from
equilibrium it follows the flow downhill (to a stable equilibrium); mu starts at the largest
|omega^2| of (K, M) and shrinks as the residual |f|_(M^-1) does (switched evolution
relaxation, at least halved by every step that lowers it; a step that makes it 100x worse is
retried with 10 mu), so the last steps are Newton's, converging quadratically. Where the
eigenvalues of M^-1 K have negative real parts (a pose above a stable one), or the step would
turn a body by more than max_rotation, the step is taken mode by mode (_step: saddle-free, with
mu raised until no body turns more: a trust region). An equilibrium found unstable (a pendulum
started upright) is left along its most unstable mode, at most max_escapes times. All matrices
are dense: statics is for mechanisms of tens of bodies (docs/decisions/statics-solver.md).

No equilibrium (a free body falling: the residual does not fall in max_iterations steps) or a
DOF of zero stiffness (neutral: every pose along it is an equilibrium) is an AnalysisError (exit
3) naming the joints whose relative motion that DOF is (and free bodies), with YAML lines; the
neutral case keeps the equilibrium row found.
"""

from __future__ import annotations

from dataclasses import field

import casadi as ca
import numpy as np
import scipy.linalg

from casmech.core import euler
from casmech.core.options import StaticsSolver
from casmech.core.records import record
from casmech.equations.functions import SystemFunctions, all_sx, build_functions
from casmech.errors import AnalysisError, BodyName, FailureContext, Interrupted
from casmech.runtime import assembly, cancel
from casmech.runtime.results import Result
from casmech.runtime.workspace import Workspace, of

DEFAULT = StaticsSolver()  # the settings of every function here (core.options)


@record(frozen=False)
class ReducedSystem:
    """Everything at one configuration q (on Phi = 0), in the independent coordinates z."""

    q: np.ndarray
    lam: np.ndarray
    residual: np.ndarray  # R = Q - Phi_q^T lam, full coordinates
    applied: np.ndarray  # Q
    basis: np.ndarray  # N, n x k, orthonormal, Phi_q N = 0
    mass: np.ndarray  # N^T M N
    stiffness: np.ndarray  # -N^T dR/dq N
    damping: np.ndarray  # -N^T dQ/dq_dot N
    force: np.ndarray  # N^T Q
    settings: StaticsSolver = field(default=DEFAULT, repr=False)

    @property
    def dof(self) -> int:
        return self.basis.shape[1]

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """(omega^2 ascending, V): eigenpairs of (sym K, M), V^T M V = I (the saddle-free
        steps' modes); computed once."""
        if not hasattr(self, "_modes"):
            if self.dof:
                self._modes = scipy.linalg.eigh(0.5 * (self.stiffness + self.stiffness.T),
                                                self.mass)
            else:
                self._modes = (np.zeros(0), np.zeros((0, 0)))
        return self._modes

    def spectrum(self) -> tuple[np.ndarray, np.ndarray]:
        """Eigenpairs of M^-1 K, ascending by real part: squared undamped frequencies (K of
        follower loads is not symmetric, so not those of sym K); computed once."""
        if not hasattr(self, "_spectrum"):
            values, vectors = np.linalg.eig(np.linalg.solve(self.mass, self.stiffness)) \
                if self.dof else (np.zeros(0), np.zeros((0, 0)))
            order = np.argsort(values.real)
            self._spectrum = (values[order], vectors[:, order])
        return self._spectrum

    def omega2(self) -> np.ndarray:
        """Real parts of the eigenvalues of M^-1 K, ascending."""
        return self.spectrum()[0].real

    def unstable(self) -> bool:
        """An eigenvalue of M^-1 K with real part below zero."""
        omega2 = self.omega2()
        return bool(omega2.size and omega2[0] < -neutral_threshold(omega2, self.settings))

    def merit(self) -> float:
        """|f| in the metric of M^-1 (an acceleration: units agree across coordinates)."""
        if not self.dof:
            return 0.0
        return float(np.sqrt(max(self.force @ np.linalg.solve(self.mass, self.force), 0.0)))


@record(frozen=False)
class Equilibrium:
    q: np.ndarray
    lam: np.ndarray
    system: ReducedSystem
    iterations: int
    escapes: int

    @property
    def residual_norm(self) -> float:
        return float(np.max(np.abs(self.system.residual), initial=0.0))


def tangent_function(functions: SystemFunctions, workspace: Workspace | None = None
                     ) -> ca.Function:
    """(t, q, lam) -> (R = Q - Phi_q^T lam, dR/dq, dQ/dq_dot, M) at q_dot = 0, built once per
    workspace from the bundle's SX functions (a compiled bundle's model is rebuilt in SX for
    AD)."""
    return of(functions, workspace).one("statics_tangent", lambda: _tangent(functions))


def _tangent(functions: SystemFunctions) -> ca.Function:
    bundle = functions
    if not all_sx(functions.functions):
        bundle = build_functions(functions.ir)
    n, m = functions.n_coordinates, functions.n_rows
    t, q, q_dot, lam = ca.SX.sym("t"), ca.SX.sym("q", n), ca.SX.sym("q_dot", n), ca.SX.sym("lam", m)
    applied = bundle["generalized_forces"](t, q, q_dot)
    phi_q = bundle["phi_q"](t, q)
    residual = applied - ca.mtimes(phi_q.T, lam)
    zero = ca.DM.zeros(n)
    outputs = [residual, ca.jacobian(residual, q), ca.jacobian(applied, q_dot),
               bundle["mass_matrix"](q)]
    outputs = [ca.substitute(out, q_dot, zero) for out in outputs]
    return ca.Function("statics_tangent", [t, q, lam], outputs)


def _factor(phi_q: np.ndarray, rank_tolerance: float):
    """Column-pivoted QR of Phi_q^T (Phi_q^T[:, pivots] = Q R) and its rank by `casmech
    check`'s cut, |R_kk| > rank_tolerance max(|R_00|, 1): a redundant row stays redundant off
    the exact pose (the Bricard loop's R_kk is ~1e-13 at |Phi| ~ 1e-12)."""
    q_factor, r_factor, pivots = scipy.linalg.qr(phi_q.T, pivoting=True)
    diagonal = np.abs(np.diag(r_factor))
    cut = rank_tolerance * max(diagonal[0] if diagonal.size else 0.0, 1.0)
    return q_factor, r_factor, pivots, int(np.sum(diagonal > cut))


def null_space(phi_q: np.ndarray, settings: StaticsSolver = DEFAULT) -> np.ndarray:
    """Orthonormal basis of {dq: Phi_q dq = 0} from the column-pivoted QR of Phi_q^T."""
    m, n = phi_q.shape
    if m == 0:
        return np.eye(n)
    q_factor, _, _, rank = _factor(phi_q, settings.assembly.linear_algebra.rank_tolerance)
    return q_factor[:, rank:]


def basis_and_rows(phi_q: np.ndarray, settings: StaticsSolver = DEFAULT
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(null_space(phi_q), the indices of a maximal set of independent rows: the QR's pivots
    up to its rank, ascending), from one factorization."""
    m, n = phi_q.shape
    if m == 0:
        return np.eye(n), np.zeros(0, int)
    q_factor, _, pivots, rank = _factor(phi_q, settings.assembly.linear_algebra.rank_tolerance)
    return q_factor[:, rank:], np.sort(pivots[:rank])


def reduced_system(functions: SystemFunctions, t: float, q: np.ndarray,
                   minimum_norm: bool = False, settings: StaticsSolver = DEFAULT,
                   workspace: Workspace | None = None) -> ReducedSystem:
    """The reduced quantities at q. lam solves Phi_q^T lam = Q in least squares: the basic
    solution of the QR (zero on redundant rows), or with `minimum_norm` the minimum-norm one
    (the reactions reported). Either gives the same residual Q - Phi_q^T lam."""
    m, n = functions.n_rows, functions.n_coordinates
    phi_q = functions.matrix("phi_q", t, q)
    applied = functions.vector("generalized_forces", t, q, np.zeros(n))
    if m == 0:
        basis, lam = np.eye(n), np.zeros(0)
    else:
        rank_tolerance = settings.assembly.linear_algebra.rank_tolerance
        q_factor, r_factor, pivots, rank = _factor(phi_q, rank_tolerance)
        basis = q_factor[:, rank:]
        lam = np.zeros(m)
        lam[pivots[:rank]] = scipy.linalg.solve_triangular(
            r_factor[:rank, :rank], q_factor[:, :rank].T @ applied)
        if minimum_norm:
            lam = np.linalg.lstsq(phi_q.T, applied, rcond=rank_tolerance)[0]
    residual, r_q, q_v, mass = (np.array(v) for v in tangent_function(functions, workspace)(
        t, q, lam))
    return ReducedSystem(q, lam, residual.ravel(), applied, basis, basis.T @ mass @ basis,
                         -basis.T @ r_q @ basis, -basis.T @ q_v @ basis, basis.T @ applied,
                         settings)


def motion_map(q: np.ndarray) -> np.ndarray:
    """T (6 nb x 7 nb): T dq stacks each body's translation and small global rotation
    2 E(p) dp for a coordinate change dq."""
    nb = q.size // 7
    t = np.zeros((6 * nb, 7 * nb))
    for k in range(nb):
        e0, e = q[3 * nb + 4 * k], q[3 * nb + 4 * k + 1:3 * nb + 4 * k + 4]
        skew = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
        t[6 * k:6 * k + 3, 3 * k:3 * k + 3] = np.eye(3)
        t[6 * k + 3:6 * k + 6, 3 * nb + 4 * k:3 * nb + 4 * k + 4] = 2 * np.column_stack(
            [-e, skew + e0 * np.eye(3)])
    return t


def body_motion(functions: SystemFunctions, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
    """(n_bodies, 6): each body's translation and small rotation (global, 2 E(p) dp) for the
    coordinate change dq (real or complex)."""
    return (motion_map(q) @ dq).reshape(functions.n_bodies, 6)


def largest_rotation(motion: np.ndarray) -> np.ndarray:
    """Per column of T dQ (6 nb x k): the largest rotation of a body."""
    nb = motion.shape[0] // 6
    rotations = motion.reshape(nb, 6, -1)[:, 3:, :]
    return np.max(np.linalg.norm(rotations, axis=1), axis=0, initial=0.0)


def model_size(functions: SystemFunctions, q: np.ndarray) -> float:
    """A length to weigh translations against rotations: the spread of the bodies and joint
    points, at least 0.1 (m)."""
    nb = functions.n_bodies
    points = [q[3 * k:3 * k + 3] for k in range(nb)]
    points += [np.asarray(j.point_i, float) for j in functions.ir.joints if j.body_i < 0]
    if len(points) < 2:
        return 0.1
    points = np.array(points)
    return max(0.1, float(np.max(np.linalg.norm(points - points.mean(axis=0), axis=1))))


def moving_parts(functions: SystemFunctions, q: np.ndarray, dq: np.ndarray, count: int = 4):
    """Joints whose relative motion dq is, and moving bodies no joint holds, with their share
    of the motion (largest first): what a failure names for a DOF."""
    motion = body_motion(functions, q, dq)
    motion = np.abs(motion) if np.iscomplexobj(motion) else motion
    length = model_size(functions, q)
    parts: list[tuple[str, object, float]] = []
    held = set()
    for joint in functions.ir.joints:
        held.update((joint.body_i, joint.body_j))
        ends = []
        for k in (joint.body_i, joint.body_j):
            if k < 0:
                ends.append((np.zeros(3), np.zeros(3), np.zeros(3)))
            else:
                ends.append((q[3 * k:3 * k + 3], motion[k, :3], motion[k, 3:]))
        at = _joint_point(functions, q, joint)
        (r_i, dr_i, dth_i), (r_j, dr_j, dth_j) = ends
        v_rel = dr_j + np.cross(dth_j, at - r_j) - dr_i - np.cross(dth_i, at - r_i)
        w_rel = dth_j - dth_i
        parts.append((joint.name, joint.source,
                      float(np.linalg.norm(w_rel) + np.linalg.norm(v_rel) / length)))
    for k, body in enumerate(functions.ir.bodies):
        if k not in held:
            size = np.linalg.norm(motion[k, 3:]) + np.linalg.norm(motion[k, :3]) / length
            parts.append((BodyName(body.name), body.source, float(size)))
    total = max((p[2] for p in parts), default=0.0)
    if total <= 0.0:
        return []
    ranked = sorted(((n, s, v / total) for n, s, v in parts if v > 1e-6 * total),
                    key=lambda item: -item[2])
    return ranked[:count]


def _joint_point(functions: SystemFunctions, q: np.ndarray, joint) -> np.ndarray:
    """Global position of the joint point on body_i."""
    k = joint.body_i
    if k < 0:
        return np.asarray(joint.point_i, float)
    nb = functions.n_bodies
    rotation = euler.numeric(euler.rotation, q[3 * nb + 4 * k:3 * nb + 4 * k + 4])
    return q[3 * k:3 * k + 3] + rotation @ np.asarray(joint.point_i, float)


def neutral_threshold(omega2: np.ndarray, settings: StaticsSolver = DEFAULT) -> float:
    """Squared frequencies |omega^2| below this count as 0: zero_omega2, or neutral_ratio
    times the largest."""
    return max(settings.zero_omega2,
               settings.neutral_ratio * float(np.max(np.abs(omega2), initial=0.0)))


def _converged(system: ReducedSystem, scale: float) -> bool:
    limit = system.settings.force_tolerance * scale
    return float(np.max(np.abs(system.residual), initial=0.0)) <= limit


def _load_scale(functions: SystemFunctions, system: ReducedSystem) -> float:
    """The largest applied generalized force or body weight, for the relative tolerance."""
    weights = [b.mass * float(np.linalg.norm(functions.ir.gravity)) for b in functions.ir.bodies]
    loads = [float(np.max(np.abs(system.applied), initial=0.0)), *weights]
    return max(max(loads), np.finfo(float).tiny)


def _step(system: ReducedSystem, mu: float) -> np.ndarray:
    """dq of one pseudo-time step: (K + mu M) dz = f. Where M^-1 K has eigenvalues below zero,
    or that step turns a body by more than max_rotation, mode by mode instead (the eigenpairs
    (omega_i^2, V_i) of (sym K, M)): amplitudes V_i^T f / (|omega_i^2| + mu) (saddle-free:
    downhill along an unstable mode, not towards the unstable pose), with mu raised, if need
    be, until no body turns by more than max_rotation (a trust region: a larger mu shortens
    the soft modes' steps most, so a mode of almost zero stiffness and roundoff force, a rod's
    spin about its axis, cannot take the whole step)."""
    settings = system.settings
    motions = motion_map(system.q) @ system.basis
    if not system.unstable():
        dz = np.linalg.solve(system.stiffness + mu * system.mass, system.force)
        if largest_rotation(motions @ dz[:, None])[0] <= settings.max_rotation:
            return system.basis @ dz
    omega2, vectors = system.modes()
    force, stiffness, turns = vectors.T @ system.force, np.abs(omega2), motions @ vectors

    def amplitudes(shift: float) -> np.ndarray:
        return force / (stiffness + shift)

    def too_far(shift: float) -> bool:
        return largest_rotation(turns @ amplitudes(shift)[:, None])[0] > settings.max_rotation

    if too_far(mu):
        low, high = mu, max(mu, settings.zero_omega2)
        while too_far(high):
            low, high = high, 4.0 * high
        for _ in range(settings.trust_bisections):  # in log(mu): high / low to ~1 % (8)
            middle = np.sqrt(max(low, settings.zero_omega2) * high)
            low, high = (middle, high) if too_far(middle) else (low, middle)
        mu = high
    return system.basis @ (vectors @ amplitudes(mu))


def _escape(functions: SystemFunctions, system: ReducedSystem) -> np.ndarray:
    """q moved off an unstable equilibrium along its most unstable mode."""
    dq = system.basis @ system.modes()[1][:, 0]
    dq = dq if dq[np.argmax(np.abs(dq))] > 0 else -dq  # a fixed sign: runs repeat
    motion = body_motion(functions, system.q, dq)
    size = max(np.max(np.linalg.norm(motion[:, 3:], axis=1), initial=0.0),
               np.max(np.linalg.norm(motion[:, :3], axis=1), initial=0.0)
               / model_size(functions, system.q))
    return system.q + dq * (system.settings.escape_rotation / size)


def _initial_mu(system: ReducedSystem) -> float:
    """A first pseudo time step of 1 / (the largest |omega^2|): overdamped for every mode."""
    return max(float(np.max(np.abs(system.omega2()), initial=0.0)), system.settings.zero_omega2)


def _try(functions: SystemFunctions, t: float, system: ReducedSystem, mu: float,
         workspace: Workspace | None = None):
    """The next iterate projected onto Phi = 0, or None when the projection fails."""
    settings = system.settings
    try:
        q = assembly.newton(functions, t, system.q + _step(system, mu),
                            settings=settings.assembly)
        return reduced_system(functions, t, q, settings=settings, workspace=workspace)
    except Interrupted:
        raise
    except (AnalysisError, np.linalg.LinAlgError):
        return None


def _polish(functions: SystemFunctions, t: float, system: ReducedSystem,
            workspace: Workspace | None = None) -> ReducedSystem:
    """Up to polish_steps Newton steps past the tolerance, each kept while it lowers the
    residual (the tolerance is met at 1e-10 of the loads; roundoff allows ~1e-15)."""
    for _ in range(system.settings.polish_steps):
        trial = _try(functions, t, system, neutral_threshold(system.omega2(), system.settings),
                     workspace)
        if trial is None or not (np.max(np.abs(trial.residual), initial=0.0)
                                 < np.max(np.abs(system.residual), initial=0.0)):
            break
        system = trial
    return system


def solve(functions: SystemFunctions, t: float = 0.0, q: np.ndarray | None = None,
          settings: StaticsSolver = DEFAULT, workspace: Workspace | None = None) -> Equilibrium:
    """The equilibrium from the assembled pose (or from q), by pseudo-transient continuation.
    Raises AnalysisError when the residual does not converge (naming the DOF it drives)."""
    workspace = of(functions, workspace)
    q = assembly.assemble_positions(functions, t, q, settings.assembly, workspace)
    system = reduced_system(functions, t, q, settings=settings, workspace=workspace)
    scale = _load_scale(functions, system)
    mu, merit, escapes = _initial_mu(system), system.merit(), 0
    for iteration in range(settings.max_iterations):
        cancel.poll()  # a cancelled run (SIGINT/SIGTERM under casmech run) stops here
        if _converged(system, scale):
            if escapes >= settings.max_escapes or not system.unstable():
                polished = _polish(functions, t, system, workspace).q
                system = reduced_system(functions, t, polished, minimum_norm=True,
                                        settings=settings, workspace=workspace)
                return Equilibrium(system.q, system.lam, system, iteration, escapes)
            escapes += 1
            escaped = assembly.newton(functions, t, _escape(functions, system),
                                      settings=settings.assembly)
            system = reduced_system(functions, t, escaped, settings=settings,
                                    workspace=workspace)
            mu, merit = _initial_mu(system), system.merit()
            continue
        trial = _try(functions, t, system, mu, workspace)
        trial_merit = np.inf if trial is None else trial.merit()
        if not np.isfinite(trial_merit) or trial_merit > 100.0 * max(merit,
                                                                     settings.zero_omega2):
            mu *= 10.0  # a step that made things far worse is not taken
            continue
        # switched evolution relaxation, accelerated: a step that lowered the residual doubles
        # the pseudo time step at least
        ratio = trial_merit / merit if merit > 0 else 1.0
        mu = max(mu * (min(ratio, settings.growth) if ratio < 1.0 else 1.0),
                 neutral_threshold(trial.omega2(), settings))
        system, merit = trial, trial_merit
    direction = system.basis @ np.linalg.solve(system.mass, system.force) if system.dof else \
        np.zeros(functions.n_coordinates)
    cause = (f"no static equilibrium found in {settings.max_iterations} iterations (unbalanced "
             f"generalized force {np.linalg.norm(system.force):.3e}); the free motion it "
             "drives (a body falling, a DOF with nothing to hold it):")
    raise AnalysisError(FailureContext(t, cause, moving_parts(functions, system.q, direction),
                                       "share of the motion"))


def neutral_directions(system: ReducedSystem) -> np.ndarray:
    """Columns dq of the DOF with zero stiffness at an equilibrium (n x count): the
    eigenvectors of M^-1 K whose eigenvalues are 0 within neutral_threshold."""
    values, vectors = system.spectrum()
    zero = np.abs(values) <= neutral_threshold(values.real, system.settings)
    if not zero.any():
        return np.zeros((system.q.size, 0))
    return system.basis @ np.linalg.qr(vectors[:, zero].real)[0]


def neutral_error(functions: SystemFunctions, t: float, equilibrium: Equilibrium,
                  directions: np.ndarray) -> AnalysisError:
    """The failure for an equilibrium that is not unique: the parts every neutral DOF moves."""
    parts: dict[str, tuple[object, float]] = {}
    for column in directions.T:
        for name, source, share in moving_parts(functions, equilibrium.q, column):
            parts[name] = (source, max(share, parts.get(name, (None, 0.0))[1]))
    ranked = sorted(((n, s, v) for n, (s, v) in parts.items()), key=lambda item: -item[2])
    cause = (f"the equilibrium is not unique: {directions.shape[1]} DOF with zero stiffness "
             "(every pose along it balances); the joints and bodies it moves:")
    return AnalysisError(FailureContext(t, cause, ranked, "share of the motion"))


def equilibrium_result(functions: SystemFunctions, t: float, equilibrium: Equilibrium,
                       analysis: str, progress=None) -> Result:
    """One row at the equilibrium (velocities and accelerations zero) and its metadata."""
    result = Result(analysis, on_row=progress)
    n = functions.n_coordinates
    result.append(t, equilibrium.q, np.zeros(n), np.zeros(n), equilibrium.lam)
    result.metadata.update(
        residual_norm=equilibrium.residual_norm, iterations=equilibrium.iterations,
        escapes=equilibrium.escapes, dof=equilibrium.system.dof,
        stable=not equilibrium.system.unstable())
    return result


def run_statics(functions: SystemFunctions, t: float = 0.0, progress=None,
                settings: StaticsSolver = DEFAULT, workspace: Workspace | None = None) -> Result:
    """The statics analysis: one results row; AnalysisError (exit 3) when there is no unique
    equilibrium (a neutral DOF keeps the row found in the error's partial result)."""
    equilibrium = solve(functions, t, settings=settings, workspace=workspace)
    result = equilibrium_result(functions, t, equilibrium, "statics", progress)
    directions = neutral_directions(equilibrium.system)
    if directions.shape[1]:
        error = neutral_error(functions, t, equilibrium, directions)
        error.partial = result
        raise error
    return result
