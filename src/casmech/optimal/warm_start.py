"""A previous `casmech optimize` result as the initial guess (`initial_guess: {file: ...}`).

The nodes' states come from results.csv's body columns (every body's x, y, z, e0..e3, vx, vy,
vz, wx, wy, wz: the r-p state, p_dot = E(p)^T omega / 2), interpolated linearly to the
problem's nodes where its grid differs; in joint coordinates they are the tree's joint
states of that r-p state (optimal/joint_model.py), each angle continued across +-pi from
node to node (np.unwrap). The controls come from controls.csv (its `t` and one column per
control, named <joint>.torque or <joint>.force), interpolated to the problem's control grid
(one value per interval, or per node for piecewise-linear controls).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from casmech.core.columns import BODY_COLUMNS
from casmech.core.records import record
from casmech.errors import UsageError
from casmech.schema.resolved import ResolvedModel
from casmech.schema.tables import TableError, read_columns


@record
class Previous:
    """The guess: states at the nodes, controls on the problem's grid."""

    times: np.ndarray
    x: np.ndarray
    u: np.ndarray
    formulation: str  # joints | bodies: what x holds

    @property
    def step(self) -> float:
        return float(self.times[1] - self.times[0])


def _read(path: str, needed: list[str]) -> dict[str, np.ndarray]:
    try:
        columns = read_columns(Path(path))
    except TableError as error:
        raise UsageError(f"initial guess: {error.message}") from None
    missing = [name for name in ["t", *needed] if name not in columns]
    if missing:
        raise UsageError(f"initial guess file '{Path(path).name}' has no column "
                         f"{', '.join(missing[:4])}; it must be a results.csv and controls.csv "
                         "of `casmech optimize` on this model")
    times = columns["t"]
    if times.size < 2 or np.any(np.diff(times) <= 0):
        raise UsageError(f"initial guess file '{Path(path).name}': t must increase, with at "
                         "least two rows")
    return columns


def _on(columns: dict[str, np.ndarray], names: list[str], times: np.ndarray) -> np.ndarray:
    """The columns at `times` (linear interpolation, the end values held outside)."""
    return np.column_stack([np.interp(times, columns["t"], columns[n]) for n in names])


def body_states(model: ResolvedModel, columns, times) -> np.ndarray:
    """(nodes, 2 n) r-p states [r; p; r_dot; p_dot] of the bodies at `times`."""
    bodies = [body.name for body in model.bodies]
    rows = _on(columns, [f"{b}.{c}" for b in bodies for c in BODY_COLUMNS[:13]], times)
    states = []
    for row in rows.reshape(len(times), len(bodies), 13):
        r, p, v, w = row[:, :3], row[:, 3:7], row[:, 7:10], row[:, 10:13]
        e0, e = p[:, :1], p[:, 1:]
        # omega = 2 E(p) p_dot, E = [-e, e~ + e0 I], E E^T = |p|^2 I: the p_dot across p
        # (a body-coordinate optimum's drift of |p| is along p, which omega does not hold)
        p_dot = 0.5 * np.column_stack([-np.sum(e * w, axis=1), e0 * w - np.cross(e, w)]
                                      ) / np.sum(p * p, axis=1, keepdims=True)
        states.append(np.concatenate([r.ravel(), p.ravel(), v.ravel(), p_dot.ravel()]))
    return np.array(states)


def solution(model: ResolvedModel, problem, joints) -> Previous:
    """The guess the problem's `guess_file` holds (joints: the JointModel, or None for body
    coordinates)."""
    results, controls = problem.guess_file
    bodies = [body.name for body in model.bodies]
    state = _read(results, [f"{b}.{c}" for b in bodies for c in BODY_COLUMNS[:13]])
    names = [control.name for control in problem.controls]
    given = _read(controls, names)
    t0 = 0.0 if joints is None else joints.t0
    times = t0 + np.linspace(0.0, problem.horizon, problem.intervals + 1)
    x = body_states(model, state, times)
    if joints is not None:
        n = len(x[0]) // 2
        x = np.array([joints.state_of(row[:n], row[n:]) for row in x])
        angles = joints.periodic()
        x[:, angles] = np.unwrap(x[:, angles], axis=0)
    per_node = joints is not None and problem.piecewise == "linear"
    grid = times if per_node else times[:-1]
    return Previous(times, x, _on(given, names, grid),
                    "bodies" if joints is None else "joints")
