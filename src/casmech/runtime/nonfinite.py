"""Results that are not finite: the failure that stops a run at the first such row, naming
the time, the results column and the elements whose values are not finite there.

A NaN or an infinity in a results row is never a result: it comes from a number beyond double
precision (a driver `angle: 1e300*t`, whose rate squared overflows in the accelerations) or
from a law evaluated where it is undefined. `Result.extend` refuses a row whose states are not
finite (NonFinite, keeping the rows before it), as do the per-row solvers before their least
squares, and output.streaming refuses a table row whose derived columns (reactions, energy)
are not. The error first knows only which state; `explain` (casmech.analyze, with the
model's functions) names the results column and blames the elements:

- constraint rows (a joint's, a driver's, a basic constraint's) whose phi, nu or gamma at the
  state is not finite, or whose rate nu is beyond the square root of the largest double (its
  square, in gamma, overflows);
- force elements (and effort motors, joint stops) whose generalized force or potential at the
  state is not finite.

The elements are evaluated at the offending row's state when it is finite, else at the last
finite row's.

A law that turns non-finite inside a solver call (a force law's `sqrt` of a negative, a `1/0`)
stops the integrator at once (SOLVER_OPTIONS: CasADi's regularity check, an unrecoverable
right-hand side failure instead of ever shorter steps), and the driver narrows the failure to
one output interval (runtime.driver): RatesNotFinite names that interval and blames the
elements at the states extrapolated over it from the last row (its q, q_dot, q_ddot).
"""

from __future__ import annotations

import math
from dataclasses import field

import casadi as ca
import numpy as np

from casmech.core.columns import JOINT_COLUMNS
from casmech.core.records import record
from casmech.errors import AnalysisError, FailureContext, solver_reason

# the integrators' options that make a non-finite right-hand side a failure at once
SOLVER_OPTIONS = {"regularity_check": True}
# the flags SUNDIALS (and runtime.dop853) return when the right-hand side (residual) failed
# unrecoverably
FAILED_RATES = ('"CV_RHSFUNC_FAIL"', '"IDA_RES_FAIL"', '"RK_RHSFUNC_FAIL"')  # (runtime.dop853)
# fractions of the failed output interval the elements are evaluated at (RatesNotFinite)
PROBES = (0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0)
OVERFLOWING = 1e150  # a rate beyond this overflows when squared (double precision: 1.8e308)
STATES = ("q", "q_dot", "q_ddot", "lam")


@record(frozen=False)
class NotFinite(FailureContext):
    """What a NonFinite names: the column and the elements (kind, name, source, what)."""

    column: str = ""
    value: float = float("nan")
    elements: list = field(default_factory=list)

    def format(self) -> str:
        at = f"at t = {self.time:.6g}: " if self.time is not None else ""
        lines = [f"analysis failed {at}{self.cause}"]
        for kind, name, source, what in self.elements:
            where = f"{source}: " if source else ""
            lines.append(f"  {where}{kind} '{name}': {what}")
        return "\n".join(lines)


def cause(column: str, value: float, named: bool) -> str:
    tail = ("; the elements not finite there:" if named else
            "; no single element: the state itself left double precision's range")
    return (f"the results are not finite from this row on ({column} = {value}); the rows "
            f"before it are kept{tail}")


class NonFinite(AnalysisError):
    """A results row that is not finite: its time, the quantity (a state of Result, a
    constraint vector, or `table` for a results column) and the index of its first entry that
    is not finite; `state` (q, q_dot) where the elements are evaluated."""

    def __init__(self, t: float, quantity: str, values, state=None, partial=None):
        values = np.ravel(np.asarray(values, float))
        bad = np.flatnonzero(~np.isfinite(values))
        self.quantity, self.index = quantity, int(bad[0]) if bad.size else 0
        self.value = float(values[self.index]) if values.size else float("nan")
        self.state, self.explained = state, False
        column = f"{quantity}[{self.index}]"
        super().__init__(NotFinite(t, cause(column, self.value, False), column=column,
                                   value=self.value), partial)

    def explain(self, functions, column: str | None = None) -> None:
        """Name the results column (or `column`) and blame the elements (module docstring);
        once."""
        if self.explained:
            return
        self.explained = True
        context = self.context
        column = column or column_of(functions, self.quantity, self.index)
        state = self.state
        if (state is None or not all(np.all(np.isfinite(v)) for v in state)) and \
                self.partial is not None and len(self.partial):
            state = (self.partial.q[-1], self.partial.q_dot[-1])
        elements = blame(functions, context.time, *state) if state is not None else []
        self.context = NotFinite(context.time, cause(column, self.value, bool(elements)),
                                 column=column, value=self.value, elements=elements)
        self.args = (self.context.format(),)


_ALL = np.logical_and.reduce
# an array's entries' sum of squares, by BLAS (one call an array, through no ufunc: NumPy's
# floating-point warnings, and the errstate that would silence them, are not involved); np.vdot's
# C function itself where NumPy exposes it (no Python dispatcher call before it). The public
# functions without that dispatcher (ndarray.dot, np.inner) warn when the sum overflows (an
# error under -W error), which np.vdot does not.
_SQUARES = getattr(np.vdot, "_implementation", np.vdot)

# the most entries one sum takes: OpenBLAS sums more than 10,000 in its threads, whose waking
# and waiting cost many times the sum's own time on a machine's other cores
PIECE = 8192


def all_finite(*arrays) -> bool:
    """Whether every entry of `arrays` is finite: from each array's sum of squares first
    (np.vdot of the array with itself: a NaN or an infinity makes it non-finite, and a sum of
    non-negative terms meets no inf - inf), entry by entry only where a sum is not finite (a
    NaN, an infinity, or finite entries whose squares overflow), a long array's in pieces of
    at most PIECE entries. The sums warn of nothing: they are the check, not news for a
    user."""
    total = 0.0
    for array in arrays:
        flat = np.asarray(array).ravel("K")  # (a view of a transposed block: np.vdot would copy)
        if flat.size <= PIECE:
            total += float(_SQUARES(flat, flat))  # (a Python float's sum overflows silently)
            continue
        for start in range(0, flat.size, PIECE):
            piece = flat[start:start + PIECE]
            total += float(_SQUARES(piece, piece))
    if math.isfinite(total):
        return True
    return all(np.isfinite(array).all() for array in arrays)


def shared(q: np.ndarray, q_dot: np.ndarray, q_ddot: np.ndarray, lam: np.ndarray) -> tuple:
    """(the array the four states view,) where they view one and it holds no more entries
    than they do (the rows' C loop's outputs of one call: runtime.joint_recorder), else the
    states: its entries finite, so are theirs (each a part of it); an entry of it outside
    them not finite only sends the check on to theirs."""
    base = q.base
    if type(base) is not np.ndarray or q_dot.base is not base or q_ddot.base is not base \
            or lam.base is not base or base.size > q.size + q_dot.size + q_ddot.size + lam.size:
        return q, q_dot, q_ddot, lam
    return (base,)


ONE_ARRAY = 256  # blocks of up to this many rows are checked as one array


def check_states(times, q, q_dot, q_ddot, lam) -> int | None:
    """The first row of a block whose states are not all finite (None: all are): all_finite
    first (a sum of squares per state, or one of the array the four states view where they
    view one no larger than them: shared), then, where one is not finite, row by row; a small
    block is searched as one array of its rows (one call into NumPy, not one per state)."""
    if all_finite(times, *shared(q, q_dot, q_ddot, lam)):
        return None
    times = np.reshape(times, (-1, 1))
    blocks = (times, q, q_dot, q_ddot, lam)
    if len(times) <= ONE_ARRAY:
        finite = _ALL(np.isfinite(np.concatenate(blocks, axis=1)), axis=1)
    else:
        finite = np.isfinite(times[:, 0])
        for block in blocks[1:]:
            finite &= _ALL(np.isfinite(block), axis=1)
    return None if _ALL(finite) else int(np.argmin(finite))


def column_of(functions, quantity: str, index: int) -> str:
    """The results column a state's entry feeds (a constraint vector's: its row's joint)."""
    nb = functions.n_bodies
    if quantity in ("phi", "nu", "gamma") or quantity == "lam":
        row = functions.rows[index] if index < functions.n_rows else None
        if row is None:
            return f"{quantity}[{index}]"
        if quantity == "lam" and row.kind != "normalization":
            return f"{row.joint}.{JOINT_COLUMNS[0]}..{JOINT_COLUMNS[-1]}"
        return f"{quantity} of {row.label}"
    if quantity not in STATES or index >= 7 * nb:
        return f"{quantity}[{index}]"
    names = functions.body_names
    translation = index < 3 * nb
    body = names[index // 3] if translation else names[(index - 3 * nb) // 4]
    if quantity == "q":
        return f"{body}.{'xyz'[index % 3]}" if translation else \
            f"{body}.e{(index - 3 * nb) % 4}"
    group = {"q_dot": ("v", "w"), "q_ddot": ("a", "alpha")}[quantity]
    suffix = f"{group[0]}{'xyz'[index % 3]}" if translation else f"{group[1]}x..{group[1]}z"
    return f"{body}.{suffix}"


def blame(functions, t: float, q, q_dot) -> list[tuple[str, str, object, str]]:
    """(kind, name, source, what) of each element whose values at (t, q, q_dot) are not
    finite (module docstring)."""
    found: dict[tuple[str, str], tuple] = {}
    vectors = {"phi": (functions, "phi", t, q), "nu": (functions, "nu", t, q),
               "gamma": (functions, "gamma", t, q, q_dot)}
    for name, (bundle, function, *args) in vectors.items():
        values = bundle.vector(function, *args)
        for row, value in zip(functions.rows, values, strict=True):
            large = name == "nu" and abs(value) > OVERFLOWING
            if np.isfinite(value) and not large:
                continue
            kind = "body" if row.kind == "normalization" else "joint"
            what = (f"its rate {name} = {value:.3g} (squared, it overflows)" if large and
                    np.isfinite(value) else f"its {name} = {value}")
            label = "p^T p - 1" if kind == "body" else row.label.split(": ", 1)[-1]
            found.setdefault((kind, row.joint), (kind, row.joint, row.source,
                                                  f"{label}: {what}"))
    for force, generalized, potential in _element_values(functions, t, q, q_dot):
        if np.all(np.isfinite(generalized)) and np.isfinite(potential):
            continue
        kind = "force" if any(force is f for f in functions.ir.forces) else "joint"
        found.setdefault((kind, force.name), (kind, force.name, force.source,
                                              "its generalized force or potential is not "
                                              "finite"))
    return list(found.values())


def _element_values(functions, t, q, q_dot):
    """(element, generalized force, potential) of every force element, effort motor and
    stop, each evaluated alone (SX built here: a failure's diagnosis, not a run's work)."""
    from casmech.equations import eom
    from casmech.equations.assemble import Coordinates

    ir = functions.ir
    x = Coordinates.create(ir.n_bodies)
    for element in (*ir.forces, *ir.motors, *ir.limits):
        generalized, potential = eom.FORCE_ELEMENTS[element.type](element, x)
        function = ca.Function("element", [x.t, x.q, x.q_dot],
                               [x.ground_fixed(ca.densify(ca.SX(generalized))),
                                x.ground_fixed(ca.SX(potential))])
        out = function(t, q, q_dot)
        yield element, np.array(out[0]).ravel(), float(out[1])


def rates_failed(error: BaseException) -> bool:
    """Whether a solver's RuntimeError is a right-hand side that was not finite."""
    return any(flag in str(error) for flag in FAILED_RATES)


def interval_failure(t0: float, t1: float, error: RuntimeError) -> AnalysisError:
    """The failure of the one output interval (t0, t1) a solver call failed on (the driver
    narrowed it: runtime.driver): equations of motion that are not finite, or what the solver
    said."""
    if rates_failed(error):
        return RatesNotFinite(t0, t1)
    why = solver_reason(error).strip().splitlines()[-1]
    return AnalysisError(FailureContext(t0, f"the integrator failed between t = {t0:.6g} and "
                                            f"{t1:.6g} ({why})"))


class RatesNotFinite(NonFinite):
    """The equations of motion not finite between the output times t0 (the last row kept) and
    t1, found by the integrator (module docstring); `explain` blames the elements at the
    states extrapolated over the interval."""

    def __init__(self, t0: float, t1: float, partial=None):
        super().__init__(t0, "rates", [float("nan")], None, partial)
        self.t0, self.t1 = t0, t1
        self._name([])

    def _name(self, elements: list) -> None:
        tail = ("; the elements not finite there (along the motion extrapolated from the last "
                "row):" if elements else "; every element is finite along the motion "
                "extrapolated from the last row: a law is undefined at the states the integrator "
                "tried")
        cause = (f"the equations of motion are not finite between t = {self.t0:.6g} and "
                 f"{self.t1:.6g} (a force law or a constraint evaluated where it is undefined); "
                 f"the rows before are kept{tail}")
        self.context = NotFinite(self.t0, cause, elements=elements)
        self.args = (self.context.format(),)

    def explain(self, functions, column: str | None = None) -> None:
        if self.explained:
            return
        self.explained = True
        elements = []
        if self.partial is not None and len(self.partial):
            t, q, q_dot = self.partial.times[-1], self.partial.q[-1], self.partial.q_dot[-1]
            q_ddot = self.partial.q_ddot[-1]
            for fraction in PROBES:
                h = fraction * (self.t1 - t)
                elements = blame(functions, t + h, q + h * q_dot + h * h / 2 * q_ddot,
                                 q_dot + h * q_ddot)
                if elements:
                    break
        self._name(elements)
