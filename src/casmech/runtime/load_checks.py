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
    check_rows([t], joints, np.reshape(values, (1, -1)))


def check_rows(times, joints: list, values: np.ndarray) -> None:
    """check_loads over rows at once (`values`: one row of friction_load's outputs per time):
    the first row that fails stops the run with its error."""
    k = len(joints)
    values = np.asarray(values, float).reshape(len(times), -1)
    finite = np.isfinite(values).all(axis=1)
    ratios = np.where(finite[:, None, None], values[:, k + 1:].reshape(-1, k, k), 0.0)
    radius = np.max(np.abs(np.linalg.eigvals(ratios)), axis=-1)
    scale = np.maximum(1.0, np.max(np.abs(np.where(finite[:, None], values[:, :k], 0.0)),
                                   axis=1))
    good = finite & (radius < 1) & (values[:, k] <= LOADS * scale)
    if good.all():
        return
    first = int(np.argmin(good))
    t, row = float(times[first]), values[first]
    if not finite[first]:  # a load vector of 0 length where a root needs it
        raise AnalysisError(FailureContext(
            t, "the loads of the joints with load parts have no finite solution",
            [(e.name, e.source, float(v)) for e, v in zip(joints, row, strict=False)],
            "load part"))
    if not radius[first] < 1:
        raise AnalysisError(FailureContext(
            t, "the friction would lock its joint(s) on their own (mu times the change of the "
            "load per unit friction force >= 1; with several joints, the spectral radius of "
            "that matrix: Painleve's paradox); give a smaller mu",
            [(e.name, e.source, float(radius[first])) for e in joints], "mu |dL/df|"))
    raise AnalysisError(FailureContext(
        t, "the loads of the joints with load parts were not solved (Newton's method did "
        "not converge from their one-joint roots)",
        [(e.name, e.source, float(row[k])) for e in joints], "residual (N or N m)"))
