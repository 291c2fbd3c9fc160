"""Forward dynamics, r-p form, integrated by SUNDIALS IDAS through CasADi.

The index-3 DAE is posed to IDAS in index-1 form: differential states x = [q, q_dot], algebraic
states z = [q_ddot, lam], with
    q' = q_dot,  q_dot' = q_ddot,
    M(q) q_ddot + Phi_q^T lam = Q(t, q, q_dot),   Phi_q q_ddot = gamma(t, q, q_dot).
Its algebraic Jacobian [M Phi_q^T; Phi_q 0] is non-singular once redundant rows are dropped (they
are found at t0 and their multipliers reported as 0). The position and velocity constraints are
not part of the index-1 system, so they drift at the integration error; after every output
IDAS call covers up to CHUNK output intervals; at the first output where the drift exceeds
DRIFT_TOLERANCE the state is projected back (Newton on Phi, then Phi_q q_dot = nu) and IDAS
restarts from there. Restarting only when needed keeps IDAS's step size and order history
(a restart every interval was 10x slower and less accurate, measured on IFToMM A01).
No user-tuned Baumgarte constants.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.compiler.checks import dependent_joints, structure
from casmech.compiler.functions import SystemFunctions
from casmech.errors import AnalysisError, FailureContext
from casmech.runtime import assembly
from casmech.runtime.kinematics import output_times
from casmech.runtime.results import Result

CHUNK = 100  # output intervals per IDAS call
DRIFT_TOLERANCE = 1e-9  # max |Phi| (and velocity-constraint residual) before projecting


def dae_problem(functions: SystemFunctions, rows: list[int]) -> dict:
    """The index-1 DAE in CasADi's semi-explicit form; time = t0 (parameter) + tau."""
    n = functions.n_coordinates
    t0, tau = ca.SX.sym("t0"), ca.SX.sym("tau")
    x, z = ca.SX.sym("x", 2 * n), ca.SX.sym("z", n + len(rows))
    t = t0 + tau
    q, q_dot, q_ddot, lam = x[:n], x[n:], z[:n], z[n:]
    phi_q = functions["phi_q"](t, q)[rows, :]
    alg = ca.vertcat(
        functions["mass_matrix"](q) @ q_ddot + phi_q.T @ lam
        - functions["generalized_forces"](t, q, q_dot),
        phi_q @ q_ddot - functions["gamma"](t, q, q_dot)[rows])
    return {"t": tau, "x": x, "z": z, "p": t0, "ode": ca.vertcat(q_dot, q_ddot), "alg": alg}


def drift(functions: SystemFunctions, t: float, q: np.ndarray, q_dot: np.ndarray) -> float:
    """Largest violation of the position and velocity constraints."""
    phi = functions.vector("phi", t, q)
    velocity = functions.matrix("phi_q", t, q) @ q_dot - functions.vector("nu", t, q)
    return float(max(np.max(np.abs(phi), initial=0.0), np.max(np.abs(velocity), initial=0.0)))


class _Stepper:
    """Integrates from a consistent state over a chunk of the output grid.

    Each call starts IDAS from a state whose derivative [q_dot, q_ddot] and algebraic states
    [q_ddot, lam] are known exactly, so they are handed over (init_xdot, z0) instead of asking
    IDACalcIC to find them (its line search failed on restarts of stiff models, measured on
    IFToMM A01 with a 1e-9 inertia)."""

    def __init__(self, functions: SystemFunctions, rows: list[int], rtol: float, atol: float):
        self.functions = functions
        self.chunk = CHUNK
        self.dae = dae_problem(functions, rows)
        self.options = {"reltol": rtol, "abstol": atol, "max_num_steps": 1000000,
                        "suppress_algebraic": True, "calc_ic": False,
                        "disable_internal_warnings": True}

    def integrate(self, t0: float, times: np.ndarray, q, q_dot, q_ddot, lam) -> np.ndarray:
        """States at `times`; on an IDAS failure, the failing interval alone is retried so the
        error names it exactly (and the caller keeps every row before it)."""
        options = self.options | {"init_xdot": list(np.concatenate([q_dot, q_ddot]))}
        integrator = ca.integrator("dynamics", "idas", self.dae, 0.0, list(times - t0), options)
        try:
            out = integrator(x0=np.concatenate([q, q_dot]), z0=np.concatenate([q_ddot, lam]),
                             p=t0)
        except RuntimeError as error:
            if len(times) > 1:
                self.chunk = 1  # from here on, one output interval per call
                return self.integrate(t0, times[:1], q, q_dot, q_ddot, lam)
            phi_q = self.functions.matrix("phi_q", t0, q)
            cause = (f"IDAS failed between t = {t0:.6g} and {times[0]:.6g} "
                     f"({str(error).splitlines()[-1].strip()}); the joints whose rows are "
                     "closest to dependent (a singular configuration?):")
            context = FailureContext(t0, cause, dependent_joints(self.functions, phi_q),
                                     "weight in the dependency")
            raise AnalysisError(context) from None
        return np.array(out["xf"].full())


def run_dynamics(functions: SystemFunctions, t_end: float, step: float, rtol: float,
                 atol: float, t0: float = 0.0) -> Result:
    result = Result("dynamics")
    n = functions.n_coordinates
    q, q_dot = assembly.initial_state(functions, t0)
    rows = list(structure(functions, t0, q).independent)
    stepper = _Stepper(functions, rows, rtol, atol)
    times = output_times(t0, t_end, step)
    k, restarts = 0, 0
    try:
        q_ddot, lam = _record(functions, result, rows, times[0], q, q_dot)
        while k < len(times) - 1:
            chunk = times[k + 1:k + 1 + stepper.chunk]
            states = stepper.integrate(times[k], chunk, q, q_dot, q_ddot, lam)
            for j, t in enumerate(chunk[:states.shape[1]]):  # fewer after a failure
                q, q_dot = states[:n, j], states[n:, j]
                k += 1
                projected = drift(functions, t, q, q_dot) > DRIFT_TOLERANCE
                if projected:
                    q = assembly.newton(functions, t, q)
                    q_dot = assembly.solve_velocities(functions, t, q, q_dot)
                    restarts += 1
                q_ddot, lam = _record(functions, result, rows, t, q, q_dot)
                if projected:
                    break  # restart IDAS from the projected state
    except AnalysisError as error:
        error.partial = result
        raise
    result.metadata.update(rtol=rtol, atol=atol, formulation="rp", integrator="idas",
                           projections=restarts)
    return result


def _record(functions, result, rows, t, q, q_dot):
    """Accelerations and multipliers at a state; append the row; return them for IDAS's z0."""
    q_ddot, lam = assembly.solve_dynamic_accelerations(functions, t, q, q_dot, rows)
    lam_full = np.zeros(functions.n_rows)
    lam_full[rows] = lam
    result.append(t, q, q_dot, q_ddot, lam_full)
    return q_ddot, lam
