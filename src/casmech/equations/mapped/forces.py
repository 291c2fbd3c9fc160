"""Applied forces (gravity and the force elements of equations.eom) as kernels mapped over the
instances of each element type: one SX kernel per (type, frame, actuator expression, which
data entries are non-zero), its parameters (points, axes, stiffness, damping, free length or
angle) as data, and the generalized forces of each instance summed into Q by a constant sparse
matrix; the kernels are the casmech.elements.force_types entries' `kernel`. A time function in a
force's
value (`value: [...]`) is evaluated outside the kernel and passed in, so forces with different
time functions share code; a spring's actuator depends on the motion and is part of its kernel
(springs with the same actuator text share it).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.elements.force_types import REGISTRY, entry_of
from casmech.elements.primitives import Frame
from casmech.equations import contact, limits, motors
from casmech.equations.assemble import Coordinates
from casmech.equations.eom import FORCE_ELEMENTS
from casmech.equations.mapped.kernels import Layout, mapped
from casmech.model.ir import GROUND_INDEX, ForceIR, ModelIR
from casmech.numerics.element_sums import assemble
from casmech.schema.resolved import ScalarFunction

ROW = 14


@dataclass(frozen=True)
class ForceKey:
    type: str
    frame: str
    actuator: tuple | None  # (text, constants) of a spring's actuator
    pattern: tuple[bool, ...]  # non-zero entries of the data (then of the value)


def _actuator_key(function: ScalarFunction | None):
    if function is None:
        return None
    return (function.text, tuple(sorted((k, float(v)) for k, v in function.constants.items())))


def data_of(force: ForceIR) -> np.ndarray:
    return REGISTRY[force.type].kernel.data(force)


def value_pattern(force: ForceIR) -> tuple[bool, ...]:
    return tuple(not c.is_zero for c in force.value) if force.value is not None else ()


def key_of(force: ForceIR) -> ForceKey:
    return ForceKey(force.type, force.frame, _actuator_key(force.actuator),
                    tuple(bool(v != 0) for v in data_of(force)) + value_pattern(force))


def _sparse_symbol(name: str, pattern) -> ca.SX:
    nz = [k for k, on in enumerate(pattern) if on]
    return ca.SX.sym(name, ca.Sparsity.triplet(len(pattern), 1, nz, [0] * len(nz)))


def _frame(x):
    return Frame(x[0:3], euler.rotation(x[3:7]))


def _digest(key: ForceKey) -> str:
    return hashlib.sha256(repr(key).encode()).hexdigest()[:8]


def n_value(key: ForceKey) -> int:
    """Entries of the value input: a force or torque vector, else none."""
    return REGISTRY[key.type].kernel.n_value


def kernel(key: ForceKey, actuator: ScalarFunction | None) -> ca.Function:
    """(x [14], x_dot [14], t, data, value) -> (generalized, potential) of one element:
    generalized over x (tsda, rsda) or body i's 7 coordinates (force, torque)."""
    n_data = len(key.pattern) - n_value(key)
    x, x_dot, t = ca.SX.sym("x", ROW), ca.SX.sym("x_dot", ROW), ca.SX.sym("t")
    data = _sparse_symbol("data", key.pattern[:n_data])
    value = _sparse_symbol("value", key.pattern[n_data:])
    frames = (x[:7], x[7:])
    generalized, potential = REGISTRY[key.type].kernel.build(
        key.type, lambda k: _frame(frames[k]), (x, x_dot, t), ca.densify(data),
        ca.densify(value), actuator, key.frame)
    return ca.Function(f"force_{key.type}_{_digest(key)}", [x, x_dot, t, data, value],
                       [generalized, potential], ["x", "x_dot", "t", "data", "value"],
                       ["generalized", "potential"])


def input_values(force: ForceIR, t, pattern):
    """The value vector at t with the sparsity of its non-zero components (MX; the SX of each
    component inlined)."""
    tt = ca.SX.sym("t")
    nonzero = [k for k, on in enumerate(pattern) if on]
    sparsity = ca.Sparsity.triplet(len(pattern), 1, nonzero, [0] * len(nonzero))
    if not nonzero:
        return ca.MX(sparsity)
    of = ca.Function("value", [tt], [ca.vertcat(*[ca.SX(force.value[k].casadi(t=tt))
                                                  for k in nonzero])])
    return ca.MX(sparsity, of.call([t], True, False)[0])


def kernelised(force: ForceIR) -> bool:
    """Whether a force element has a kernel: a type whose entry has one, whose laws read no
    other state than t and its own length/angle and rate (equations.coordinates binds the
    others)."""
    laws = ([force.actuator] if force.actuator is not None else []) + list(force.value or ())
    entry = entry_of(force.type)
    return entry is not None and entry.kernel is not None and \
        not any(getattr(f, "states", None) for f in laws)


def on_ground(force: ForceIR) -> bool:
    """Whether an element acts on ground only (a one-body type on ground): no generalized
    force."""
    return getattr(entry_of(force.type), "one_body", False) and force.body_i == GROUND_INDEX


def unrolled(ir: ModelIR, force: ForceIR) -> ca.Function:
    """(t, q, q_dot) -> (generalized, potential) of one element as equations.eom writes it, over
    the whole model's coordinates: for the elements without a kernel (their code grows with
    their number, not with the model's)."""
    x = Coordinates.create(ir.n_bodies)
    generalized, energy = FORCE_ELEMENTS[force.type](force, x)
    prefix = "stop_" if force.type in limits.COORDINATE else "force_"  # a stop: its joint's name
    name = prefix + "".join(c if c.isalnum() else "_" for c in force.name)
    return ca.Function(name, [x.t, x.q, x.q_dot],
                       [x.ground_fixed(ca.SX(generalized)), x.ground_fixed(ca.SX(energy))])


def applied(ir: ModelIR, t, q, q_dot) -> tuple:
    """(sum of the force elements' generalized forces [n], their potential energy), MX."""
    layout = Layout(ir.n_bodies)
    padded, padded_dot = layout.pad_q(q), layout.pad(q_dot, 7)
    groups: dict = {}
    total, potential = ca.MX(layout.n, 1), ca.MX(0)
    for force in (*ir.forces, *ir.motors, *ir.limits):  # motors and stops: eom's elements
        if on_ground(force):
            continue
        if kernelised(force):
            groups.setdefault(key_of(force), []).append(force)
        else:
            term, energy = unrolled(ir, force)(t, q, padded_dot[:layout.n])
            total, potential = total + term, potential + energy
    for key, members in groups.items():
        term, energy = _group(key, members, layout, (t, padded, padded_dot))
        total, potential = total + term, potential + energy
    return total, potential


def _group(key: ForceKey, members: list[ForceIR], layout: Layout, state) -> tuple:
    t, padded, padded_dot = state
    function, count = kernel(key, members[0].actuator), len(members)
    width = function.size1_out(0)
    columns = [(layout.q(f.body_i) + layout.q(f.body_j))[:width] for f in members]
    flat = [c for f in members for c in layout.q(f.body_i) + layout.q(f.body_j)]
    split = len(key.pattern) - n_value(key)
    chosen = [k for k, on in enumerate(key.pattern[:split]) if on]
    data = np.concatenate([data_of(f)[chosen] for f in members])
    values = ca.horzcat(*[input_values(f, t, key.pattern[split:]) for f in members]) \
        if n_value(key) else ca.DM(0, count)
    generalized, energy = mapped(function, count)(
        ca.reshape(padded[flat], ROW, count), ca.reshape(padded_dot[flat], ROW, count), t,
        ca.DM(ca.repmat(function.sparsity_in(3), 1, count), data), values)
    entries = [(column, width * k + c) for k, cs in enumerate(columns)
               for c, column in enumerate(cs) if column < layout.n]
    if not entries:
        return ca.MX(layout.n, 1), ca.sum2(energy)
    rows, positions = (np.array(items) for items in zip(*entries, strict=True))
    total = assemble([(layout.n, 1, rows, np.zeros(len(rows), int), positions)],
                      [generalized])[0]
    return total, ca.sum2(energy)


def motor_reactions(ir: ModelIR, t, q, q_dot) -> tuple:
    """(force, torque) (3 x joints) the effort motors of ir.motors add to their joints'
    reactions (equations.eom.reactions), per motor from equations.motors over the whole model's
    coordinates, like the elements without a kernel."""
    n_joints = len(ir.joints)
    force, torque = ca.MX(3, n_joints), ca.MX(3, n_joints)
    column = {joint.name: k for k, joint in enumerate(ir.joints)}
    for motor in (*ir.motors, *ir.limits):
        k = column[motor.name]
        joint = ir.joints[k]
        x = Coordinates.create(ir.n_bodies)
        at = x.point(joint.body_i, joint.point_i)
        reaction = limits.reaction if motor.type in limits.COORDINATE else motors.reaction
        pair = [x.ground_fixed(ca.SX(e)) for e in reaction(motor, x, at)]
        prefix = "stop_" if motor.type in limits.COORDINATE else "motor_"
        name = prefix + "".join(c if c.isalnum() else "_" for c in motor.name)
        f_motor, t_motor = ca.Function(name, [x.t, x.q, x.q_dot], pair)(t, q, q_dot)
        select = ca.DM(ca.Sparsity.triplet(1, n_joints, [0], [k]), 1.0)
        force, torque = force + f_motor @ select, torque + t_motor @ select
    return force, torque


def element_outputs(ir: ModelIR, t, q, q_dot):
    """The contacts' and stops' results columns (equations.contact.element_outputs), one SX
    function over the whole model's coordinates (a few per model: no kernel)."""
    x = Coordinates.create(ir.n_bodies)
    values = x.ground_fixed(ca.SX(contact.element_outputs(ir, x)))
    return ca.Function("element_outputs", [x.t, x.q, x.q_dot], [values])(t, q, q_dot)
