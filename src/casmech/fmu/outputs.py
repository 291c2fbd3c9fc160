"""The FMU's outputs: the results columns of the results contract (docs/format.md), as one
CasADi expression of the state.

The row is runtime.results.row_function's (the joint states and `outputs:` last) over the bundle whose functions take the model data
[d; u] last (equations.functions over fmu.model's IR), with each joint's reaction columns in
the frame its `reactions:` names and its torque about its reaction point
(runtime.reaction_frames, here in CasADi on the row's q). The column `t` is FMI's time and is
not an output.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Sequence

import casadi as ca

from casmech.core import euler
from casmech.equations import readings
from casmech.equations.functions import SystemFunctions
from casmech.errors import UsageError
from casmech.model.ir import GROUND_INDEX, JointIR
from casmech.runtime.results import column_names


def names(bundle: SystemFunctions) -> list[str]:
    """Every results column but t, in the contract's order."""
    return column_names(bundle)[1:]


def chosen(bundle: SystemFunctions, patterns: Sequence[str] | None) -> list[int]:
    """Indices into `names` of the columns `patterns` names (names or globs such as
    'crank.*', in the columns' order); None: all."""
    every = names(bundle)
    if patterns is None:
        return list(range(len(every)))
    picked: set[int] = set()
    for pattern in patterns:
        found = [k for k, name in enumerate(every) if fnmatch.fnmatchcase(name, pattern)]
        if not found:
            close = [n for n in every if pattern.split(".")[0] == n.split(".")[0]][:8]
            hint = f"; columns of '{pattern.split('.')[0]}': {', '.join(close)}" if close else \
                "; see the header of a run's results.csv for the names"
            raise UsageError(f"--outputs {pattern}: no results column of the model matches"
                             + hint)
        picked.update(found)
    return sorted(picked)


def _rotation(q, n_bodies: int, k: int):
    if k == GROUND_INDEX:
        return ca.SX.eye(3)
    p = q[3 * n_bodies + 4 * k:3 * n_bodies + 4 * k + 4]
    return euler.rotation(p / ca.norm_2(p))


def _written(joint: JointIR, q, n_bodies: int, force, torque) -> ca.SX:
    """A joint's reaction columns as the table writes them (module docstring)."""
    a_i = _rotation(q, n_bodies, joint.body_i)
    if joint.reaction_point is not None:
        arm = a_i @ (ca.SX(joint.point_i) - ca.SX(joint.reaction_point))
        torque = torque + ca.cross(arm, force)
    frames = {"global": lambda: ca.SX.eye(3), "body_i": lambda: a_i,
              "body_j": lambda: _rotation(q, n_bodies, joint.body_j),
              "joint": lambda: a_i @ ca.horzcat(*(ca.SX(joint.geometry[f"{axis}@i"])
                                                  for axis in "uvw"))}
    rotation = frames[joint.reaction_frame]()
    return ca.vertcat(rotation.T @ force, rotation.T @ torque)


def row(bundle: SystemFunctions, t, q, q_dot, q_ddot, lam, data, symbols: ca.SX) -> ca.SX:
    """The results row but t (a column) at the state; `data` the bundle's trailing input,
    `symbols` the symbols the bundle was built over ([d; u], fmu.model.Exported.data)."""
    functions, ir, nb = bundle.functions, bundle.ir, bundle.n_bodies
    omega, alpha = functions["body_rates"](q, q_dot, q_ddot, data)
    force, torque = functions["reactions"](t, q, q_dot, lam, data)
    kinetic, potential = functions["energy"](t, q, q_dot, data)
    phi = functions["phi"](t, q, data)
    violation = ca.mmax(ca.fabs(phi)) if phi.numel() else ca.SX(1, 1)
    parts = []
    for k in range(nb):
        parts += [q[3 * k:3 * k + 3], q[3 * nb + 4 * k:3 * nb + 4 * k + 4],
                  q_dot[3 * k:3 * k + 3], omega[:, k], q_ddot[3 * k:3 * k + 3], alpha[:, k]]
    parts += [_written(joint, q, nb, force[:, j], torque[:, j])
              for j, joint in enumerate(ir.joints)]
    parts += [kinetic + potential, violation, functions["element_outputs"](t, q, q_dot, data),
              readings.columns_function(ir, symbols)(t, q, q_dot, q_ddot, force, torque, data)]
    values = ca.densify(ca.vertcat(*parts))
    assert values.numel() == len(names(bundle)), "the row and the contract's columns differ"
    return values

