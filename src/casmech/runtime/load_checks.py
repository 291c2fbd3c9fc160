"""The check of solved joint friction loads (equations/friction_load.py), one for dynamics
segments (runtime/friction.py) and prescribed motions (runtime/kinematics.py, and a driven
coordinate's in dynamics: runtime/driven_friction.py): the loads of the joints with load parts
must be finite, unique and solved, else the run stops with an analysis error naming the
joints."""

from __future__ import annotations

import numpy as np

from casmech.errors import AnalysisError, FailureContext

LOADS = 1e-10  # the largest residual (relative) of solved friction loads: a roundoff floor


def check_loads(t: float, joints: list, values: np.ndarray) -> None:
    """Stop at time t where the loads `values` (friction_load's outputs: g_1..g_k, the
    residual, A row by row) of `joints` are not finite, not unique (A's spectral radius >= 1:
    Painleve's paradox) or not solved (a residual above LOADS of the largest load part)."""
    k = len(joints)
    if not np.all(np.isfinite(values)):  # a load vector of 0 length where a root needs it
        raise AnalysisError(FailureContext(
            t, "the loads of the joints with load parts have no finite solution",
            [(e.name, e.source, float(v)) for e, v in zip(joints, values, strict=False)],
            "load part"))
    radius = float(np.max(np.abs(np.linalg.eigvals(values[k + 1:].reshape(k, k)))))
    if not radius < 1:
        raise AnalysisError(FailureContext(
            t, "the friction would lock its joint(s) on their own (mu times the change of the "
            "load per unit friction force >= 1; with several joints, the spectral radius of "
            "that matrix: Painleve's paradox); give a smaller mu",
            [(e.name, e.source, radius) for e in joints], "mu |dL/df|"))
    scale = max(1.0, float(np.max(np.abs(values[:k]))))
    if not values[k] <= LOADS * scale:
        raise AnalysisError(FailureContext(
            t, "the loads of the joints with load parts were not solved (Newton's method did "
            "not converge from their one-joint roots)",
            [(e.name, e.source, float(values[k])) for e in joints], "residual (N or N m)"))


def check_rows(times, joints: list, values: np.ndarray) -> None:
    """check_loads over rows at once (`values`: one row of friction_load's outputs per time):
    the first row that fails stops the run with its error."""
    k = len(joints)
    values = np.asarray(values, float).reshape(len(times), -1)
    finite = np.isfinite(values).all(axis=1)
    ratios = np.where(finite[:, None, None], values[:, k + 1:].reshape(-1, k, k), 0.0)
    radius = np.max(np.abs(np.linalg.eigvals(ratios)), axis=-1)
    scale = np.maximum(1.0, np.max(np.abs(values[:, :k]), axis=1))
    good = finite & (radius < 1) & (values[:, k] <= LOADS * scale)
    if not good.all():
        first = int(np.argmin(good))
        check_loads(float(times[first]), joints, values[first])
