"""The joints' `initial:` values as rows that assembly holds (runtime/initial_holds.py).

A position row per given coordinate, its value at q less the target (scaled by `scale`,
assembly's continuation from the file's pose, where every coordinate is 0): an angle's (a
coordinate kind with `cos_sin`, casmech.elements.coordinate_kinds, or a universal joint's)
difference wrapped to (-pi, pi] (atan2 of its sine and cosine), a displacement's as it is, a
spherical joint's rotation as the vector part of conj(target^scale) (x) the relative rotation
(3 rows, 0 where they agree). A rate row per given rate: the rate (linear in q_dot) whose
value the velocities must meet. The formulas are equations/coordinates.py's and
joint_states.py's (the columns the results table writes), so a held value is the one the
results show at t = 0.
"""

from __future__ import annotations

import casadi as ca

from casmech.core.quaternions import conjugate, product
from casmech.core.records import record
from casmech.core.values import constant
from casmech.elements.coordinate_kinds import REGISTRY as KINDS
from casmech.equations import coordinates, joint_states
from casmech.equations.assemble import Coordinates
from casmech.model.bindings import coordinate_geometry
from casmech.model.ir import ModelIR, RowInfo

# the scalar position keys beyond the coordinate kinds' (a universal joint's angles, which wrap)
UNIVERSAL = ("angle_i", "angle_j")


def scalars() -> tuple[str, ...]:
    """The scalar position keys: each coordinate kind's, then a universal joint's."""
    return (*KINDS, *UNIVERSAL)


def wrapped() -> frozenset[str]:
    """The position keys whose difference wraps to (-pi, pi]: the kinds that come back to
    themselves after a turn (`cos_sin`), and a universal joint's angles."""
    return frozenset({name for name, kind in KINDS.items() if kind.cos_sin is not None}
                     | set(UNIVERSAL))


def rate_keys() -> tuple[str, ...]:
    """The rate keys (`initial:` and state attribute alike)."""
    return (*(kind.rate for kind in KINDS.values()), *(f"{key}_dot" for key in UNIVERSAL))


@record
class Held:
    """The rows of one kind: residuals (positions) or rates with their targets."""

    values: ca.SX  # position residuals, or the rates (linear in q_dot)
    targets: ca.SX  # rates' targets (positions: empty)
    rows: tuple[RowInfo, ...]


def _label(joint, key: str, value) -> str:
    shown = "given" if isinstance(value, (ca.SX, ca.MX)) else \
        ("[" + ", ".join(f"{float(v):.6g}" for v in ca.DM(value).full().ravel()) + "]"
         if ca.DM(value).numel() > 1 else f"{float(ca.DM(value)):.6g}")
    return f"{joint.type} '{joint.name}': initial {key} = {shown}"


def _power(target, scale):
    """target^scale: the rotation of Euler parameters `target` by a fraction of its angle."""
    if isinstance(scale, (int, float)) and scale == 1:
        return target
    half = ca.atan2(ca.norm_2(target[1:4]), target[0])
    axis = target[1:4] / ca.fmax(ca.norm_2(target[1:4]), 1e-300)
    return ca.vertcat(ca.cos(scale * half), ca.sin(scale * half) * axis)


def positions(ir: ModelIR, x: Coordinates, scale=1.0) -> Held:
    """The position rows of every joint's given coordinates, in file order."""
    values, rows = [], []
    for joint in ir.joints:
        if not joint.initial:
            continue
        geometry = coordinate_geometry(joint)
        source = joint.initial_sources
        wrap = wrapped()
        for key in scalars():
            if key in joint.initial:
                target = scale * constant(joint.initial[key])
                error = coordinates.JOINT_VALUES[key](geometry, x) - target
                values.append(ca.atan2(ca.sin(error), ca.cos(error)) if key in wrap
                              else error)
                rows.append(RowInfo(joint.name, "initial", _label(joint, key,
                                                                  joint.initial[key]),
                                    source.get(key, joint.source)))
        if "orientation" in joint.initial:
            target = _power(constant(joint.initial["orientation"]), scale)
            relative = joint_states.relative_rotation(geometry, x)
            values.append(product(conjugate(target), relative)[1:4])
            rows += [RowInfo(joint.name, "initial", _label(joint, "orientation",
                                                           joint.initial["orientation"]),
                             source.get("orientation", joint.source))] * 3
    return Held(_stack(values), ca.SX(0, 1), tuple(rows))


def rates(ir: ModelIR, x: Coordinates) -> Held:
    """The rate rows of every joint's given rates (file order) and their targets."""
    values, targets, rows = [], [], []
    for joint in ir.joints:
        geometry = coordinate_geometry(joint) if joint.initial else None
        for key in rate_keys():
            if key in joint.initial:
                values.append(coordinates.JOINT_VALUES[key](geometry, x))
                targets.append(constant(joint.initial[key]))
                rows.append(RowInfo(joint.name, "initial", _label(joint, key,
                                                                  joint.initial[key]),
                                    joint.initial_sources.get(key, joint.source)))
        if "angular_velocity" in joint.initial:
            values.append(joint_states.relative_angular_velocity(geometry, x))
            targets.append(constant(joint.initial["angular_velocity"]))
            rows += [RowInfo(joint.name, "initial", _label(
                joint, "angular_velocity", joint.initial["angular_velocity"]),
                joint.initial_sources.get("angular_velocity", joint.source))] * 3
    return Held(_stack(values), _stack(targets), tuple(rows))


def _stack(items):
    return ca.vertcat(*items) if items else ca.SX(0, 1)


def span(ir: ModelIR) -> float:
    """The largest given coordinate (radians, metres; a rotation's angle): how far assembly's
    continuation goes (numeric IR)."""
    largest = 0.0
    for joint in ir.joints:
        for key in scalars():
            if key in joint.initial:
                largest = max(largest, abs(float(joint.initial[key])))
        if "orientation" in joint.initial:
            e = ca.DM(joint.initial["orientation"]).full().ravel()
            largest = max(largest, 2 * float(ca.atan2(ca.norm_2(ca.DM(e[1:])), abs(e[0]))))
    return largest
