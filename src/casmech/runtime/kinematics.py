"""Kinematic analysis of a fully driven (0-DOF) mechanism, and inverse dynamics on top of it.

At each output time: positions by Newton from a second-order predictor, velocities from
Phi_q q_dot = nu, accelerations from Phi_q q_ddot = gamma; then the multipliers from the
equations of motion with the prescribed motion, Phi_q^T lam = Q - M q_ddot (inverse dynamics).
With a fully driven mechanism the two analyses differ only in what they are asked for; both
report the joint reactions, since the prescribed motion determines them.
"""

from __future__ import annotations

import numpy as np

from casmech.compiler.checks import structure
from casmech.compiler.functions import SystemFunctions
from casmech.errors import AnalysisError, Diagnostic, ModelError
from casmech.runtime import assembly
from casmech.runtime.results import Result


def output_times(t0: float, t_end: float, step: float) -> np.ndarray:
    n = int(np.floor((t_end - t0) / step + 1e-9))
    times = t0 + step * np.arange(n + 1)
    return times if times[-1] >= t_end - 1e-9 * step else np.append(times, t_end)


def require_fully_driven(functions: SystemFunctions, t: float, q: np.ndarray,
                         analysis: str) -> None:
    report = structure(functions, t, q)
    if report.dof == 0:
        return
    raise ModelError([Diagnostic(
        "E501", "analysis.type",
        f"{analysis} needs a fully driven mechanism, but this one has {report.dof} "
        "degree(s) of freedom at the assembled configuration",
        functions.ir.analysis.source, expected="0 degrees of freedom", got=f"{report.dof}",
        hint="add drivers (`driver: {angle: ...}` on a revolute joint, `f:` on a basic "
             "constraint) or run a dynamics analysis")])


def state_at(functions: SystemFunctions, t: float, q_guess: np.ndarray, q_dot_guess: np.ndarray):
    q = assembly.newton(functions, t, q_guess)
    q_dot = assembly.solve_velocities(functions, t, q, q_dot_guess)
    q_ddot = assembly.solve_kinematic_accelerations(functions, t, q, q_dot)
    lam = assembly.solve_multipliers(functions, t, q, q_dot, q_ddot)
    return q, q_dot, q_ddot, lam


def run_prescribed_motion(functions: SystemFunctions, t_end: float, step: float,
                          analysis: str = "kinematics", t0: float = 0.0,
                          progress=None) -> Result:
    result = Result(analysis, on_row=progress)
    q = assembly.assemble_positions(functions, t0)
    require_fully_driven(functions, t0, q, analysis)
    q_dot = np.zeros(functions.n_coordinates)
    q_ddot = np.zeros(functions.n_coordinates)
    previous = t0
    try:
        for t in output_times(t0, t_end, step):
            h = t - previous
            q, q_dot, q_ddot, lam = state_at(functions, t, q + h * q_dot + 0.5 * h * h * q_ddot,
                                             q_dot + h * q_ddot)
            result.append(t, q, q_dot, q_ddot, lam)
            previous = t
    except AnalysisError as error:
        error.partial = result
        raise
    return result


def run_assembly(functions: SystemFunctions, t0: float = 0.0, progress=None) -> Result:
    """One state at t0: assembled positions, velocities projected from the file's, and the
    accelerations and multipliers the equations of motion give at that instant."""
    result = Result("assembly", on_row=progress)
    q, q_dot = assembly.initial_state(functions, t0)
    q_ddot, lam = assembly.solve_dynamic_accelerations(functions, t0, q, q_dot)
    result.append(t0, q, q_dot, q_ddot, lam)
    return result
