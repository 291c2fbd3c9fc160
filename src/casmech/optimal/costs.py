"""The Lagrange and Mayer terms of an optimal control problem in joint coordinates, as CasADi
functions of (t, x, c) on optimal/joint_model.py's model (c = [controls; design]).

    integrand(t, x, c) = sum_i w_i e_i(t, x, c)^2 + sum_j w_j (column_j - table_j(t))^2
    final(t, x, c)     = the `final` expression, as written

e_i are the `integral:` expressions, of t, the parameters (a decision parameter is its
variable) and every results column. The terms are squared so that any expression, whatever
its sign, is a cost bounded below (a state-quadratic LQR cost is `{x: q}`); the Mayer term is
taken as written, so it can reward (`-cart.y`) as well as penalise.

The transcription integrates the integrand as one more state with the ODE (optimal/
joint_ocp.py): the collocation's quadrature at its points, RK4's stages in multiple shooting.
"""

from __future__ import annotations

from collections.abc import Mapping

import casadi as ca
import numpy as np

from casmech.core.expressions import ExpressionError
from casmech.core.expressions import parse as parse_expression
from casmech.core.records import record
from casmech.errors import UsageError
from casmech.optimal.joint_model import JointModel
from casmech.schema.resolved import ScalarFunction

ANGLES = ("angle", "angle_i", "angle_j")  # joint state columns that are angles


@record
class Terms:
    integrand: ca.Function | None  # (t, x, c) -> the Lagrange integrand; None: no such term
    final: ca.Function | None  # (t, x, c) -> the Mayer term; None: no such term


def used(problem) -> bool:
    """Whether the problem has Lagrange, tracking or Mayer terms."""
    return bool(problem.integral or problem.track or problem.final is not None)


def _environment(model: JointModel, problem, columns: ca.Function, t, x, c) -> dict:
    """Every name an expression may read: t, the results columns (`columns`: `continued`'s,
    angles continued past pi), the decision parameters."""
    values = columns(t, x, c)
    environment = {name: values[k] for k, name in enumerate(model.names)}
    environment["t"] = t
    design = [c[model.n_u + k] for k in range(len(problem.parameters))]
    for name, design_value in zip(problem.parameters, design, strict=True):
        environment[name] = design_value
    for name, function in model.derived.items():  # parameters of decision parameters
        environment[name] = function(*design)
    return environment


def continued(model: JointModel) -> ca.Function:
    """(t, x, c) -> every results column, each angle column that follows a joint coordinate
    (_angles) continued past pi as that coordinate goes: what cost terms, `terminal:`,
    `terminal_bounds:`, `initial:` and `path:` read."""
    t, x, c = model.symbols
    values = model.columns(t, x, c)
    rows = ca.vertsplit(values)
    for name, (slot, sign, offset) in _angles(model).items():
        k = model.names.index(name)
        turns = ca.floor((sign * x[slot] + offset - rows[k]) / (2 * np.pi) + 0.5)
        rows[k] = rows[k] + 2 * np.pi * turns
    return ca.Function("continued_columns", [t, x, c], [ca.vertcat(*rows)],
                       ["t", "x", "c"], ["columns"])


def _angles(model: JointModel, step: float = 1e-3) -> dict:
    """Angle columns (in (-pi, pi] in the results table) that follow one periodic joint
    coordinate x_i as sign * x_i + offset modulo 2 pi: column -> (i, sign, offset). In the
    cost terms such a column is that continuous value (a swing-up's end angle is pi + 2 pi k
    as the coordinate says, without the table's jump)."""
    x0 = np.asarray(model.start[0], float)
    c0 = np.concatenate([np.zeros(model.n_u), model.design_values])

    def columns(x):
        return np.array(model.columns(model.t0, x, c0).full()).ravel()

    base, found = columns(x0), {}
    angles = [k for k, name in enumerate(model.names) if name.rpartition(".")[2] in ANGLES]
    for slot in model.periodic():
        for direction in (step, -step):  # one of them does not cross the table's jump
            moved = x0.copy()
            moved[slot] += direction
            rate = (columns(moved) - base) / direction
            for k in angles:
                if abs(abs(rate[k]) - 1) < 1e-6 and model.names[k] not in found:
                    sign = float(np.sign(rate[k]))
                    found[model.names[k]] = (slot, sign, base[k] - sign * x0[slot])
    return found


def parsed(problem, parameters: Mapping[str, float]) -> dict:
    """The problem's `integral` and `final` as resolved functions where the API gave texts
    (expression -> weight; an expression): the fields to replace."""
    def function(text: str) -> ScalarFunction:
        try:
            expr = parse_expression(text)
        except ExpressionError as error:
            raise UsageError(f"cost term '{text}': {error.message}") from None
        return ScalarFunction(text, expr, dict(parameters), ())

    integral = {text: term if isinstance(term, tuple) else (function(text), float(term))
                for text, term in problem.integral.items()}
    final = function(problem.final) if isinstance(problem.final, str) else problem.final
    return {"integral": integral, "final": final}


def _value(term: ScalarFunction, text: str, environment: Mapping):
    """A term in CasADi."""
    expr, constants = term.expr, dict(term.constants)
    missing = sorted(name for name in expr.symbols
                     if name not in environment and name not in constants)
    if missing:
        raise UsageError(f"'{text}' reads {', '.join(missing)}, not a results column of the "
                         "joint formulation, a parameter or t")
    return expr.evaluate({**constants, **environment}, "casadi")


def terms(model: JointModel, problem, columns: ca.Function) -> Terms:
    """The problem's cost terms on the model, reading the results columns of `columns`
    (`continued(model)`)."""
    t, x, c = model.symbols
    environment = _environment(model, problem, columns, t, x, c) if used(problem) else {}
    integrand = 0
    for text, term in problem.integral.items():
        function, weight = term
        integrand += float(weight) * _value(function, text, environment) ** 2
    for column, (reference, weight) in problem.track.items():
        value = environment[model.names[model.column(column)]]
        integrand += float(weight) * (value - reference.casadi(t=t)) ** 2
    final = problem.final
    mayer = None if final is None else _value(final, final.text, environment)
    return Terms(
        ca.Function("lagrange", [t, x, c], [integrand]) if problem.integral or problem.track
        else None,
        None if mayer is None else ca.Function("mayer", [t, x, c], [mayer]))


def with_quadrature(rhs: ca.Function, integrand: ca.Function, n_x: int) -> ca.Function:
    """(t, [x; q], c) -> [x'; integrand]: the ODE with the running cost as a last state."""
    t, x, c = (ca.SX.sym(name, size) for name, size in
               (("t", 1), ("x", n_x + 1), ("c", rhs.size1_in(2))))
    state = x[:n_x]
    return ca.Function("rhs_with_cost", [t, x, c],
                       [ca.vertcat(rhs(t, state, c), integrand(t, state, c))])

