"""Forward dynamics in the r-p or r-omega form, integrated by SUNDIALS IDAS through CasADi.

State x = [q, v] with v = q_dot (r-p) or [r_dot; omega_bar] (r-omega). IDAS integrates
x' = [q_dot(q, v), v_dot(t, q, v)], where v_dot comes from the augmented-Lagrangian solution of
the constrained equations of motion (compiler.augmented), which stays well-posed through
singular configurations and with redundant joints. The position and velocity constraints hold at
the integration error; at the first output where either drifts past DRIFT_TOLERANCE the state is
projected back, mass-orthogonally (assembly.project), and IDAS restarts from there. No
Baumgarte constants.

Measured on IFToMM A02 (the N-four-bar through its flat poses) this passes every singular
configuration, where the index-1 DAE [M P^T; P 0] of the previous version failed at the first.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.compiler import augmented, euler
from casmech.compiler.checks import dependent_joints
from casmech.compiler.functions import SystemFunctions
from casmech.errors import AnalysisError, FailureContext
from casmech.runtime import assembly
from casmech.runtime.kinematics import output_times
from casmech.runtime.results import Result

CHUNK = 64  # most output intervals per IDAS call
MAX_STEPS = 50000  # IDAS steps per output interval before it gives up (IDA_TOO_MUCH_WORK)
DRIFT_TOLERANCE = 1e-9  # max |Phi| before projecting; velocities: this over the output step


def penalty(functions: SystemFunctions, form: augmented.Formulation, t, q) -> float:
    """The augmented-Lagrangian penalty scaled to the model: PENALTY max(diag M) / max(diag
    P^T P), so a s^2 ~ PENALTY for the constraint modes whatever the units."""
    mass = functions.matrix(form.mass, q)
    return augmented.PENALTY * np.max(np.diag(mass), initial=1.0)


def velocities(functions: SystemFunctions, name: str, q, q_dot) -> np.ndarray:
    """The formulation's v from r-p velocities: omega_bar = 2 G(p) p_dot for r-omega."""
    if name == "rp":
        return np.array(q_dot, float)
    nb = functions.n_bodies
    omega_bar = [2 * euler.numeric(euler.g_matrix, q[3 * nb + 4 * k:3 * nb + 4 * k + 4])
                 @ q_dot[3 * nb + 4 * k:3 * nb + 4 * k + 4] for k in range(nb)]
    return np.concatenate([q_dot[:3 * nb], *omega_bar])


class _Stepper:
    """Integrates from a state over a chunk of the output grid; one IDAS integrator per relative
    output grid, reused for every restart (time enters as the parameter t0)."""

    def __init__(self, functions: SystemFunctions, name: str, rtol: float, atol: float,
                 penalty_value: float):
        self.functions, self.penalty = functions, penalty_value
        self.chunk = CHUNK
        self.ode = augmented.ode(functions.functions, name)
        self.options = {"reltol": rtol, "abstol": atol, "max_num_steps": MAX_STEPS,
                        "disable_internal_warnings": True}
        self.cache: dict[tuple, ca.Function] = {}

    def adapt(self, used: int, projected: bool) -> None:
        """Next chunk: twice the intervals used before a projection (the rest of a chunk after
        one is discarded), or twice the last chunk, up to CHUNK."""
        self.chunk = min(CHUNK, 2 * used if projected else 2 * self.chunk)

    def integrator(self, grid: np.ndarray) -> ca.Function:
        key = tuple(np.round(grid, 12))
        if key not in self.cache:
            self.cache[key] = ca.integrator("dynamics", "idas", self.ode, 0.0, list(grid),
                                            self.options)
        return self.cache[key]

    def integrate(self, t0: float, times: np.ndarray, x: np.ndarray) -> np.ndarray:
        """States at `times`; on an IDAS failure, the failing interval alone is retried so the
        error names it exactly (and the caller keeps every row before it)."""
        try:
            out = self.integrator(times - t0)(x0=x, p=[t0, self.penalty])
            states = np.array(out["xf"].full())
        except RuntimeError as error:
            states, error_text = None, str(error).splitlines()[-1].strip()
        if states is not None and np.all(np.isfinite(states)):
            return states
        if len(times) > 1:
            self.chunk = 1  # from here on, one output interval per call
            return self.integrate(t0, times[:1], x)
        why = error_text if states is None else "the state became NaN or infinite"
        q = x[:self.functions.n_coordinates]
        cause = (f"IDAS failed between t = {t0:.6g} and {times[0]:.6g} ({why}); the joints "
                 "whose rows are closest to dependent (a singular configuration?):")
        context = FailureContext(t0, cause, dependent_joints(
            self.functions, self.functions.matrix("phi_q", t0, q)), "weight in the dependency")
        raise AnalysisError(context)


def run_dynamics(functions: SystemFunctions, t_end: float, step: float, rtol: float,
                 atol: float, t0: float = 0.0, formulation: str = "rp",
                 progress=None) -> Result:
    form = augmented.FORMULATIONS[formulation]
    result = Result("dynamics", on_row=progress)
    n = functions.n_coordinates
    q, q_dot = assembly.initial_state(functions, t0)
    v = velocities(functions, formulation, q, q_dot)
    a = penalty(functions, form, t0, q)
    stepper = _Stepper(functions, formulation, rtol, atol, a)
    record = _Recorder(functions, formulation, result, a)
    times = output_times(t0, t_end, step)
    k, restarts = 0, 0
    try:
        record(times[0], q, v)
        while k < len(times) - 1:
            chunk = times[k + 1:k + 1 + stepper.chunk]
            states = stepper.integrate(times[k], chunk, np.concatenate([q, v]))
            for j, t in enumerate(chunk[:states.shape[1]]):  # fewer after a failure
                q, v = states[:n, j], states[n:, j]
                k += 1
                projected = drifted(functions, form, t, q, v, step)
                if projected:
                    q, v = assembly.project(functions, form, t, q, v, a)
                    restarts += 1
                record(t, q, v)
                if projected:
                    break  # restart IDAS from the projected state
            stepper.adapt(j + 1, projected)
    except AnalysisError as error:
        error.partial = result
        raise
    result.metadata.update(rtol=rtol, atol=atol, formulation=formulation, integrator="idas",
                           accelerations="augmented Lagrangian", projections=restarts)
    return result


def drifted(functions: SystemFunctions, form: augmented.Formulation, t: float, q, v,
            step: float) -> bool:
    """Whether |Phi| passed DRIFT_TOLERANCE, or the velocity-constraint residual passed what
    would move the positions by as much before the next output."""
    phi = functions.vector("phi", t, q)
    velocity = functions.matrix(form.jacobian, t, q) @ v - functions.vector(form.nu, t, q)
    return bool(np.max(np.abs(phi), initial=0.0) > DRIFT_TOLERANCE
                or np.max(np.abs(velocity), initial=0.0) * step > DRIFT_TOLERANCE)


class _Recorder:
    """Appends a results row (r-p velocities, accelerations and all multipliers) for a state."""

    def __init__(self, functions: SystemFunctions, name: str, result: Result, penalty_value):
        self.functions, self.name, self.result = functions, name, result
        self.solve = augmented.accelerations(functions.functions, name)
        self.penalty = penalty_value

    def __call__(self, t: float, q: np.ndarray, v: np.ndarray) -> None:
        v_dot, lam = (np.array(out.full()).ravel() for out in
                      self.solve(t, q, v, self.penalty))
        if self.name == "rp":
            self.result.append(t, q, v, v_dot, lam)
            return
        q_dot, q_ddot = self.functions.evaluate("romega_to_rp", q, v, v_dot)
        lam_full = np.zeros(self.functions.n_rows)  # normalization rows carry no reaction
        lam_full[:len(lam)] = lam
        self.result.append(t, q, q_dot.ravel(), q_ddot.ravel(), lam_full)
