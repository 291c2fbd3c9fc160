"""Force elements as kernels: one SX kernel per (type, frame, actuator expression, which data
entries are non-zero), its parameters (points, axes, stiffness, damping, free length or angle)
as data, the kernels being the casmech.elements.force_types entries' `kernel`; an element
without one (a type without a kernel, a law reading other joints' state, a symbolic model's
element) is its law (equations.force_laws) over the model's coordinates, a function of its own.
A time function in a force's value (`value: [...]`) is evaluated outside the kernel and passed
in, so forces with different time functions share code; a spring's actuator depends on the
motion and is part of its kernel (springs with the same actuator text share it).

`instances` sorts a model's elements into both, for every builder of applied forces (the system
functions, formulations.residuals).
"""

from __future__ import annotations

import hashlib

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.core.records import record
from casmech.elements.force_types import REGISTRY, entry_of
from casmech.elements.primitives import Frame
from casmech.equations import evaluation, friction, limits
from casmech.equations.evaluation import Evaluation
from casmech.equations.force_laws import FORCE_ELEMENTS, elements
from casmech.equations.symbols import Coordinates
from casmech.model.ir import GROUND_INDEX, ForceIR, ModelIR
from casmech.schema.resolved import ScalarFunction

ROW = 14  # x of an element: [r_i, p_i, r_j, p_j]


@record
class ForceKey:
    """What makes two force elements share one kernel: type, frame, actuator and data
    pattern."""

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
    return ca.SX.sym(name, evaluation.sparse_column(pattern))


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


def input_values(force: ForceIR, t, pattern, ev: Evaluation):
    """The value vector at t with the sparsity of its non-zero components (the SX of each
    component inlined)."""
    tt = ca.SX.sym("t")
    nonzero = [k for k, on in enumerate(pattern) if on]
    sparsity = evaluation.sparse_column(pattern)
    if not nonzero:
        return ev.sym(sparsity)
    value = ca.vertcat(*[ca.SX(force.value[k].casadi(t=tt)) for k in nonzero])
    return ev.sym(sparsity, ev.apply([tt], [value], [t])[0])


def kernelised(force: ForceIR) -> bool:
    """Whether a force element is evaluated through its type's kernel: an element of a type
    whose entry has one, its numbers numbers, whose laws read no other state than t and its own
    length/angle and rate (equations.coordinates binds the others)."""
    laws = ([force.actuator] if force.actuator is not None else []) + list(force.value or ())
    entry = entry_of(force.type)
    return entry is not None and entry.kernel is not None and numbers(force) and \
        not any(getattr(f, "states", None) for f in laws)


def numbers(force: ForceIR) -> bool:
    """Whether an element's data and law constants are numbers (a kernel's data and key), not
    symbols of the model data."""
    values = [*force.params.values(), *force.points.values(), *force.axes.values()]
    for law in ([force.actuator] if force.actuator is not None else []) + list(force.value or ()):
        values += list(law.constants.values())
    return not any(isinstance(v, (ca.SX, ca.MX)) for v in values)


def on_ground(force: ForceIR) -> bool:
    """Whether an element acts on ground only (a one-body type on ground): no generalized
    force."""
    return getattr(entry_of(force.type), "one_body", False) and force.body_i == GROUND_INDEX


def unrolled_name(force: ForceIR) -> str:
    """The C name of an element's own function (a stop, a friction: its joint's name)."""
    prefix = ("stop_" if force.type in limits.COORDINATE else
              "friction_" if force.type in friction.COORDINATE else "force_")
    return prefix + "".join(c if c.isalnum() else "_" for c in force.name)


def law(force: ForceIR):
    """x -> [generalized force over q, potential] of an element by its type's law
    (equations.force_laws)."""
    return lambda x: [ca.SX(value) for value in FORCE_ELEMENTS[force.type](force, x)]


def unrolled(ir: ModelIR, force: ForceIR, data: ca.SX | None = None) -> ca.Function:
    """(t, q, q_dot (, d)) -> (generalized, potential) of one element by its law, over the whole
    model's coordinates: an element without a kernel (its code grows with the number of such
    elements, not with the model's). `data`: the symbols of a symbolic IR, its last input."""
    x = Coordinates.create(ir.n_bodies)
    outputs = [x.ground_fixed(value) for value in law(force)(x)]
    extra = [] if data is None else [data]
    return ca.Function(unrolled_name(force), [x.t, x.q, x.q_dot, *extra], outputs)


def instances(ir: ModelIR, kernels: bool = True) -> tuple[dict, list]:
    """(kernel key -> its elements, the elements without a kernel (every element when not
    `kernels`)), in the file's order; elements on ground only are left out."""
    groups: dict = {}
    plain = []
    for force in elements(ir):
        if on_ground(force):
            continue
        if kernels and kernelised(force):
            groups.setdefault(key_of(force), []).append(force)
        else:
            plain.append(force)
    return groups, plain


def group_data(key: ForceKey, members: list[ForceIR], t, ev: Evaluation) -> tuple:
    """(the chosen data entries (count x n), the values at t (value pattern x count)) of a
    kernel's elements."""
    count = len(members)
    split = len(key.pattern) - n_value(key)
    chosen = [k for k, on in enumerate(key.pattern[:split]) if on]
    data = np.array([data_of(f)[chosen] for f in members]).reshape(count, len(chosen))
    values = ca.horzcat(*[input_values(f, t, key.pattern[split:], ev) for f in members]) \
        if n_value(key) else ca.DM(0, count)
    return data, values
