"""The bodies' initial state from the joints' `initial:` values (docs/format.md#initial-state).

The file's pose is the reference: every joint coordinate is 0 there. Along the spanning tree
(casmech.elements.joint_tree) each body is placed by a rigid motion of the reference frame,
D_child = D_parent o M (M^-1 when the tree joint is traversed from its body_j), M being the
tree joint's motion by its initial values in the reference (global) frame:

- a type's coordinates (casmech.elements.coordinate_kinds, each kind's `pose`): angle a,
  displacement s (rotation about its axis w through its point P, slide along w):
  x -> R_w(a) (x - P) + P + s w (a coordinate that follows another, a screw's slide, is the
  other's value times its ratio: s = lead a / (2 pi));
- universal angle_i, angle_j: R = R_axis_i(angle_i) R_axis_j(angle_j) about P (the cross
  frame's Rx Ry, formulations/tree.py);
- spherical orientation R0, angular_velocity w0: R = R(phi) R0 about P, phi = 0 with rate w0
  (R(phi): Euler parameters unit([1, phi / 2]), exact to first order, which is what the rate
  needs);

a coordinate not given is 0 (the reference), a rate not given 0. A body is then at r = D(r0),
p = d (x) p0 (d: D's Euler parameters). A root of the tree (a floating body) keeps its pose in
the file and moves by its own velocity and angular velocity (a rotation about its centre of
mass with rate omega and a translation with rate v, both 0 at t = 0), which its tree children
share. Velocities are the time derivatives of the poses along the coordinates' rates, by AD.
Only the parts of the mechanism where a joint has `initial:` are posed; a part without keeps
the file's poses and velocities.

The motions are one SX Function of the coordinates, their rates and the geometry, evaluated
on numbers, or on traced numbers' expressions (casmech.core.traced) when any input is one,
so the posed state of a model with symbolic parameters carries its derivatives exactly.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.core import euler, traced
from casmech.core.quaternions import conjugate, product, unit
from casmech.elements.joint_types import COORDINATES, REGISTRY
from casmech.model.ir import BodyIR


class _Inputs:
    """The inputs of the posing Function: an SX symbol per value (numbers or traced)."""

    def __init__(self):
        self.symbols: list[ca.SX] = []
        self.values: list = []

    def add(self, value) -> ca.SX:
        array = traced.asarray(value).reshape(-1)
        symbol = ca.SX.sym(f"x{len(self.symbols)}", array.size)
        self.symbols.append(symbol)
        self.values += list(array)
        return symbol


class _Motions:
    """The coordinates (their values and rates) the tree's motions depend on."""

    def __init__(self, inputs: _Inputs):
        self.inputs = inputs
        self.c: list[ca.SX] = []
        self.c_dot: list[ca.SX] = []

    def coordinate(self, value, rate) -> ca.SX:
        symbol = self.inputs.add(value)
        self.c.append(symbol)
        self.c_dot.append(self.inputs.add(rate))
        return symbol


def _rotation(axis, angle):
    return ca.vertcat(ca.cos(angle / 2), ca.sin(angle / 2) * axis)


def _about(point, rotation, shift=0.0):
    """(Euler parameters, translation) of x -> R (x - point) + point + shift."""
    return rotation, point - euler.rotation(rotation) @ point + shift


def _coordinates_motion(motions: _Motions, joint, frame, inputs: _Inputs):
    """The motion by a joint's coordinates: each kind's `pose` by its value, composed."""
    entry, given = REGISTRY[joint.type], joint.initial
    point = inputs.add(frame["P"])
    added: dict = {}

    def quantity(name: str):
        if name not in added:
            added[name] = inputs.add(frame[name])
        return added[name]

    rotation, shift, values = None, None, {}
    for name, kind in COORDINATES.items():
        if name not in entry.coordinates:
            continue
        if name in entry.follows:  # its value is another coordinate's times a ratio
            base, ratio = entry.follows[name]
            value = values[base] * inputs.add(ratio(joint.options))
        else:
            value = motions.coordinate(given.get(kind.name, 0.0), given.get(kind.rate, 0.0))
        values[name] = value
        turn, slide = kind.pose(quantity, value)
        if turn is not None:
            rotation = turn if rotation is None else product(rotation, turn)
        if slide is not None:
            shift = slide if shift is None else shift + slide
    return _about(point, ca.DM([1, 0, 0, 0]) if rotation is None else rotation,
                  ca.DM.zeros(3) if shift is None else shift)


def _universal_motion(motions: _Motions, joint, frame, inputs: _Inputs):
    given = joint.initial
    point = inputs.add(frame["P"])
    first = _rotation(inputs.add(frame["axis_i"]),
                      motions.coordinate(given.get("angle_i", 0.0), given.get("angle_i_dot", 0.0)))
    second = _rotation(inputs.add(frame["axis_j"]),
                       motions.coordinate(given.get("angle_j", 0.0),
                                          given.get("angle_j_dot", 0.0)))
    return _about(point, product(first, second))


def _spherical_motion(motions: _Motions, joint, frame, inputs: _Inputs):
    given = joint.initial
    point = inputs.add(frame["P"])
    start = inputs.add(given.get("orientation", np.array([1.0, 0, 0, 0])))
    phi = motions.coordinate(np.zeros(3), given.get("angular_velocity", np.zeros(3)))
    return _about(point, product(unit(ca.vertcat(1, phi / 2)), start))


# `initial:` keys beyond the coordinates' (joint_types.JointType.initial) -> its motion
MOTIONS = {
    ("angle_i", "angle_i_dot", "angle_j", "angle_j_dot"): _universal_motion,
    ("orientation", "angular_velocity"): _spherical_motion,
}


def _motion(motions: _Motions, joint, frame, inputs: _Inputs):
    extra = REGISTRY[joint.type].initial
    if extra:
        return MOTIONS[extra](motions, joint, frame, inputs)
    if set(REGISTRY[joint.type].coordinates) <= set(COORDINATES) and joint.initial:
        return _coordinates_motion(motions, joint, frame, inputs)
    return ca.DM([1, 0, 0, 0]), ca.DM.zeros(3)  # held at the reference


def _compose(first, second):
    """first o second, each (Euler parameters, translation)."""
    return product(first[0], second[0]), euler.rotation(first[0]) @ second[1] + first[1]


def _inverse(motion):
    rotation = conjugate(motion[0])
    return rotation, -(euler.rotation(rotation) @ motion[1])


def _root_motion(motions: _Motions, body: BodyIR, inputs: _Inputs):
    """A floating root's own motion: about its CM by omega, along v (0 at t = 0)."""
    centre = inputs.add(body.r0)
    phi = motions.coordinate(np.zeros(3), body.omega0)
    shift = motions.coordinate(np.zeros(3), body.r_dot0)
    return _about(centre, unit(ca.vertcat(1, phi / 2)), shift)


def posed_bodies(model, bodies: tuple[BodyIR, ...], frames) -> tuple[BodyIR, ...]:
    """The bodies at their initial state (module docstring); `bodies` as in the file,
    `frames`: joint name -> its global joint frame at the file's pose (model.lower)."""
    from casmech.elements.joint_tree import GROUND, Link, spanning_tree

    joints = model.joints
    if not any(joint.initial for joint in joints):
        return bodies
    names = [body.name for body in bodies]
    links = [Link(j.name, j.type, j.body_i, j.body_j, j.cut) for j in joints]
    tree = spanning_tree(names, links)
    root = tree.root_of()
    posed = {root[name] for j in joints if j.initial for name in (j.body_i, j.body_j)}
    inputs = _Inputs()
    motions = _Motions(inputs)
    index = {name: k for k, name in enumerate(names)}
    identity = (ca.DM([1, 0, 0, 0]), ca.DM.zeros(3))
    moved = {GROUND: identity} | {name: _root_motion(motions, bodies[index[name]], inputs)
                                  for name in tree.roots if name in posed}
    for tree_joint in tree.joints:
        if root[tree_joint.child] not in posed:
            continue
        joint = joints[tree_joint.index]
        motion = _motion(motions, joint, frames[joint.name], inputs)
        if tree_joint.reversed(links):
            motion = _inverse(motion)
        moved[tree_joint.child] = _compose(moved[tree_joint.parent], motion)
    chosen = [k for k, name in enumerate(names) if name in moved]
    return _evaluate(bodies, chosen, [moved[names[k]] for k in chosen], inputs, motions)


def _evaluate(bodies, chosen, moved, inputs: _Inputs, motions: _Motions):
    """The bodies `chosen` placed by their motions `moved`, with the velocities along the
    coordinates' rates; the others as they are."""
    r0 = [inputs.add(bodies[k].r0) for k in chosen]
    p0 = [inputs.add(bodies[k].p0) for k in chosen]
    p = [product(d, start) for (d, _), start in zip(moved, p0, strict=True)]
    r = [euler.rotation(d) @ start + shift for (d, shift), start in zip(moved, r0, strict=True)]
    c, c_dot = ca.vertcat(*motions.c), ca.vertcat(*motions.c_dot)
    rates = [ca.jtimes(ca.vertcat(*r, *p), c, c_dot)] if motions.c else []
    rates = ca.vertsplit(rates[0], [0, 3 * len(r), 3 * len(r) + 4 * len(p)]) if rates else \
        [ca.SX.zeros(3 * len(r)), ca.SX.zeros(4 * len(p))]
    omega = [2 * euler.e_matrix(pk) @ rates[1][4 * n:4 * n + 4] for n, pk in enumerate(p)]
    outputs = ca.vertcat(*r, *p, rates[0], *omega)
    values = _values(ca.Function("posed", [ca.vertcat(*inputs.symbols)], [outputs]),
                     inputs.values)
    n = len(chosen)
    out = list(bodies)
    for m, k in enumerate(chosen):
        pick = {"r0": values[3 * m:3 * m + 3], "p0": values[3 * n + 4 * m:3 * n + 4 * m + 4],
                "r_dot0": values[7 * n + 3 * m:7 * n + 3 * m + 3],
                "omega0": values[10 * n + 3 * m:10 * n + 3 * m + 3]}
        out[k] = BodyIR(bodies[k].name, bodies[k].mass, bodies[k].inertia, **pick,
                        source=bodies[k].source)
    return tuple(out)


def _values(function: ca.Function, items: list) -> np.ndarray:
    """function(items) as numbers, or as traced numbers where an item is one."""
    numbers = np.array(function(np.array([traced.value(v) for v in items], float))).ravel()
    if not any(traced.is_traced(v) for v in items):
        return numbers
    expressions = function(ca.vertcat(*(traced.expression(traced.asarray(v)) for v in items)))
    return traced.array([traced.Traced(numbers[k], expressions[k]) if
                         not expressions[k].is_constant() else numbers[k]
                         for k in range(numbers.size)])
