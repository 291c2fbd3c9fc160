"""Results of an analysis and their table per the results contract (MODEL_FORMAT.md)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from casmech.compiler.functions import SystemFunctions

BODY_COLUMNS = ("x", "y", "z", "e0", "e1", "e2", "e3", "vx", "vy", "vz", "wx", "wy", "wz",
                "ax", "ay", "az", "alphax", "alphay", "alphaz")
JOINT_COLUMNS = ("fx", "fy", "fz", "tx", "ty", "tz")


@dataclass
class Result:
    """States at the output times; q_ddot and lam complete the state where known.
    on_row, when given, is called with the time of every row as it is appended (progress)."""

    analysis: str
    times: list[float] = field(default_factory=list)
    q: list[np.ndarray] = field(default_factory=list)
    q_dot: list[np.ndarray] = field(default_factory=list)
    q_ddot: list[np.ndarray] = field(default_factory=list)
    lam: list[np.ndarray] = field(default_factory=list)
    metadata: dict = field(default_factory=dict)
    on_row: Callable[[float], None] | None = field(default=None, repr=False, compare=False)

    def append(self, t, q, q_dot, q_ddot, lam) -> None:
        self.times.append(float(t))
        for store, value in ((self.q, q), (self.q_dot, q_dot), (self.q_ddot, q_ddot),
                             (self.lam, lam)):
            store.append(np.array(value, float))
        if self.on_row is not None:
            self.on_row(float(t))

    def __len__(self) -> int:
        return len(self.times)


def column_names(functions: SystemFunctions) -> list[str]:
    names = ["t"]
    names += [f"{b}.{c}" for b in functions.body_names for c in BODY_COLUMNS]
    names += [f"{j.name}.{c}" for j in functions.joints for c in JOINT_COLUMNS]
    return names + ["energy", "constraint_violation"]


def row(functions: SystemFunctions, t, q, q_dot, q_ddot, lam) -> np.ndarray:
    """One row of the results table."""
    nb = functions.n_bodies
    omega, alpha = functions.evaluate("body_rates", q, q_dot, q_ddot)
    per_body = [
        np.concatenate([q[3 * k:3 * k + 3], q[3 * nb + 4 * k:3 * nb + 4 * k + 4],
                        q_dot[3 * k:3 * k + 3], omega[:, k], q_ddot[3 * k:3 * k + 3], alpha[:, k]])
        for k in range(nb)
    ]
    force, torque = functions.evaluate("reactions", t, q, q_dot, lam)
    per_joint = [np.concatenate([force[:, j], torque[:, j]]) for j in range(len(functions.joints))]
    kinetic, potential = functions.evaluate("energy", t, q, q_dot)
    violation = np.max(np.abs(functions.vector("phi", t, q)), initial=0.0)
    return np.concatenate([[t], *per_body, *per_joint, [(kinetic + potential).item(), violation]])


def table(functions: SystemFunctions, result: Result) -> tuple[list[str], np.ndarray]:
    names = column_names(functions)
    rows = [row(functions, *state) for state in
            zip(result.times, result.q, result.q_dot, result.q_ddot, result.lam, strict=True)]
    return names, np.array(rows).reshape(len(rows), len(names))
