"""The force elements' quantities of a model (equations.force_kernels), evaluated by an
Evaluation: the generalized applied force and its potential, the effort motors' and stops' share
of the joint reactions, the contacts' and stops' results columns, each defined here once.

Inline, every element is its law over the model's coordinates, in one graph with the rows (a
body's frame computed once for all); mapped, the generalized forces of each kernel's elements
are summed into Q by a constant sparse matrix, and an element without a kernel is its own
function over the model's coordinates.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.equations import contact, force_kernels, friction, limits, motors
from casmech.equations.evaluation import Evaluation
from casmech.equations.rows import Layout
from casmech.equations.symbols import Coordinates
from casmech.model.ir import ForceIR, ModelIR
from casmech.numerics.element_sums import assemble

ROW = force_kernels.ROW


def over_coordinates(ir: ModelIR, ev: Evaluation, name: str, build, t, q, q_dot) -> list:
    """build(x), a list of expressions over the model's coordinates x (a force law, a motor's
    reaction), ground fixed, at (t, q, q_dot): inline, built over these symbols themselves;
    mapped, a function (t, q, q_dot (, d)) of its own, called."""
    if ev.inline:  # (an argument that is not a symbol, e.g. q_dot(q, v): substituted after)
        given = [t, q, q_dot]
        symbols = [a if a.is_valid_input() else ca.SX.sym("a", a.sparsity()) for a in given]
        x = Coordinates(*symbols, ca.SX.sym("q_ddot", q.numel()), ca.SX.sym("q_ground", 7),
                        ir.n_bodies)
        outputs = [x.ground_fixed(ca.SX(e)) for e in build(x)]
        moved = [(s, a) for s, a in zip(symbols, given, strict=True) if s is not a]
        if moved:
            outputs = ca.substitute(outputs, [s for s, _ in moved], [a for _, a in moved])
        return outputs
    x = Coordinates.create(ir.n_bodies)
    outputs = [x.ground_fixed(ca.SX(e)) for e in build(x)]
    extra = [ev.data] if ev.symbolic else []
    function = ca.Function(name, [x.t, x.q, x.q_dot, *extra], outputs)
    return function.call([t, q, q_dot, *([ev.input] if extra else [])])


def applied(ir: ModelIR, ev: Evaluation, t, q, q_dot, start=None) -> tuple:
    """(`start` (gravity) + the sum of the force elements' generalized forces [n], their
    potential energy): inline the elements are added to `start` one by one, mapped their sum
    is added to it."""
    layout = Layout(ir.n_bodies)
    padded, padded_dot = layout.pad_q(q), layout.pad(q_dot, 7)
    groups, plain = force_kernels.instances(ir, kernels=not ev.inline)
    if ev.inline:  # one graph: every element's law over the same frames
        start = 0 if start is None else start
        if not plain:
            return start + ca.SX(layout.n, 1), ca.SX(0)
        return tuple(over_coordinates(ir, ev, "applied", lambda x: _sum(plain, x, start), t, q,
                                      q_dot))
    total, potential = ev.sym(layout.n, 1), ev.sym(0)
    for force in plain:
        term, energy = over_coordinates(ir, ev, force_kernels.unrolled_name(force),
                                        force_kernels.law(force), t, q, padded_dot[:layout.n])
        total, potential = total + term, potential + energy
    for key, members in groups.items():
        term, energy = _group(key, members, layout, ev, (t, padded, padded_dot))
        total, potential = total + term, potential + energy
    return (total if start is None else start + total), potential


def _sum(elements: list[ForceIR], x, start) -> list:
    """[start + the elements' generalized forces, their potential] by their laws over x."""
    total, potential = start, 0
    for force in elements:
        generalized, energy = force_kernels.law(force)(x)
        total, potential = total + generalized, potential + energy
    return [total, potential]


def _group(key: force_kernels.ForceKey, members: list[ForceIR], layout: Layout,
           ev: Evaluation, state) -> tuple:
    t, padded, padded_dot = state
    function, count = force_kernels.kernel(key, members[0].actuator), len(members)
    width = function.size1_out(0)
    columns = [(layout.q(f.body_i) + layout.q(f.body_j))[:width] for f in members]
    flat = [c for f in members for c in layout.q(f.body_i) + layout.q(f.body_j)]
    data, values = force_kernels.group_data(key, members, t, ev)
    generalized, energy = ev.call(
        function, count, ca.reshape(padded[flat], ROW, count),
        ca.reshape(padded_dot[flat], ROW, count), t,
        ca.DM(ca.repmat(function.sparsity_in(3), 1, count), data.ravel()), values)
    entries = [(column, width * k + c) for k, cs in enumerate(columns)
               for c, column in enumerate(cs) if column < layout.n]
    if not entries:
        return ev.sym(layout.n, 1), ca.sum2(energy)
    rows, positions = (np.array(items) for items in zip(*entries, strict=True))
    total = assemble([(layout.n, 1, rows, np.zeros(len(rows), int), positions)],
                     [generalized])[0]
    return total, ca.sum2(energy)


def motor_reactions(ir: ModelIR, ev: Evaluation, t, q, q_dot) -> tuple:
    """(force, torque) (3 x joints) the effort motors and stops add to their joints'
    reactions, per element a function over the model's coordinates (a few per model)."""
    n_joints = len(ir.joints)
    column = {joint.name: k for k, joint in enumerate(ir.joints)}
    elements = (*ir.motors, *(e for e in ir.limits if e.type not in friction.COORDINATE))
    if ev.inline and elements:  # one graph over the same frames
        return tuple(over_coordinates(ir, ev, "motor_reactions",
                                      lambda x: _reactions(ir, elements, column, x), t, q, q_dot))
    force, torque = ev.sym(3, n_joints), ev.sym(3, n_joints)
    for motor in elements:
        stop = motor.type in limits.COORDINATE
        name = ("stop_" if stop else "motor_") + "".join(
            c if c.isalnum() else "_" for c in motor.name)
        f_motor, t_motor = over_coordinates(
            ir, ev, name, lambda x, motor=motor: _reactions(ir, (motor,), column, x, 1), t, q,
            q_dot)
        select = ca.DM(ca.Sparsity.triplet(1, n_joints, [0], [column[motor.name]]), 1.0)
        force, torque = force + f_motor @ select, torque + t_motor @ select
    return force, torque


def _reactions(ir: ModelIR, elements, column: dict, x, n_columns: int | None = None) -> list:
    """[force, torque] (3 x joints, or 3 x 1 for n_columns=1) of effort motors and stops on
    their joints' body_j, the torque about body_i's joint point, by their laws over x."""
    n_columns = len(ir.joints) if n_columns is None else n_columns
    force, torque = ca.SX(3, n_columns), ca.SX(3, n_columns)
    for motor in elements:
        joint = ir.joints[column[motor.name]]
        reaction = limits.reaction if motor.type in limits.COORDINATE else motors.reaction
        f_motor, t_motor = reaction(motor, x, x.point(joint.body_i, joint.point_i))
        if n_columns == 1:
            force, torque = force + f_motor, torque + t_motor
        else:
            k = column[motor.name]
            force[:, k] += f_motor
            torque[:, k] += t_motor
    return [force, torque]


def element_outputs(ir: ModelIR, ev: Evaluation, t, q, q_dot):
    """The contacts' and stops' results columns (equations.contact.element_outputs), one
    function over the model's coordinates."""
    return over_coordinates(ir, ev, "element_outputs", lambda x: [contact.element_outputs(ir, x)],
                            t, q, q_dot)[0]
