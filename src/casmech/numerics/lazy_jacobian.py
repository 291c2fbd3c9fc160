"""A Function whose Jacobian CasADi builds cheaply: forward sweeps mapped over the columns.

SUNDIALS integrators created through casadi.integrator build the Jacobian of their right-hand
side when they are constructed, even when they never evaluate it (CVODES's Adams method with
functional iteration), which by symbolic differentiation of the articulated-body ODE grows
out of reach with the tree (docs/decisions/lazy-jacobian.md). `forward_jacobian` gives the
function a custom Jacobian made of one forward-mode derivative mapped over the unit seeds:
built in about the time of that one derivative, exact to roundoff, evaluated in n forward
sweeps when a Newton iteration needs it.
"""

from __future__ import annotations

import casadi as ca
import numpy as np


def forward_jacobian(function: ca.Function, exact: bool = True,
                     given: ca.Function | None = None) -> ca.Function:
    """`function` with the custom Jacobian of the module docstring (an MX call of it, so a
    compiled function stays compiled), or `given` (a Function of jacobian()'s signature, built
    once by the caller: creating an integrator then builds no Jacobian); exact=False: declared
    not differentiable, for an integrator that never evaluates the Jacobian (CVODES's
    functional iteration), since creating one still analyses the Jacobian's sparsity for a
    linear solver (a dense one for a large tree: docs/decisions/lazy-jacobian.md)."""
    symbols = function.mx_in()
    custom = given if given is not None else jacobian(function) if exact else None
    options = ({"custom_jacobian": custom, "jac_penalty": 0} if exact
               else {"is_diff_in": [False] * function.n_in()})
    return ca.Function(function.name(), symbols, function.call(symbols), function.name_in(),
                       function.name_out(), options)


def jacobian(function: ca.Function) -> ca.Function:
    """(inputs, outputs) -> every output's Jacobian by every input (CasADi's order), by forward
    sweeps mapped over unit seeds."""
    n_in, n_out = function.n_in(), function.n_out()
    inputs = [ca.MX.sym(function.name_in(k), function.sparsity_in(k)) for k in range(n_in)]
    outputs = [ca.MX.sym(function.name_out(k), function.sparsity_out(k)) for k in range(n_out)]
    sweep = function.forward(1)
    zeros = [ca.MX.zeros(function.sparsity_in(k).shape) for k in range(n_in)]
    blocks = {}
    for k, x in enumerate(inputs):
        n = x.numel()
        seeds = [ca.repmat(z, 1, n) for z in zeros]
        seeds[k] = ca.MX.eye(n)
        columns = sweep.map(n).call([*inputs, *outputs, *seeds])
        for o in range(n_out):
            blocks[o, k] = columns[o]
    names_in, names_out = function.name_in(), function.name_out()
    return ca.Function(
        f"jac_{function.name()}", [*inputs, *outputs],
        [blocks[o, k] for o in range(n_out) for k in range(n_in)],
        [*names_in, *names_out],
        [f"jac_{o}_{i}" for o in names_out for i in names_in])


def data_jacobian(function: ca.Function, name: str | None = None) -> ca.Function:
    """The Function jacobian() of `function` without its trailing input (the model data of a
    parametric build: never differentiated, bound at run time) would give: inputs, then nominal
    outputs, then that trailing input; every output's Jacobian by every other input (SX, by
    symbolic AD: what a compiled library holds, so no column of the data is computed; one
    Jacobian of the stacked outputs, so the blocks share their work)."""
    inputs = function.sx_in()
    outputs = function.call(inputs)
    nominal = [ca.SX.sym(function.name_out(k), function.sparsity_out(k))
               for k in range(function.n_out())]
    names_in, names_out = function.name_in()[:-1], function.name_out()
    whole = ca.jacobian(ca.vertcat(*map(ca.vec, outputs)), ca.vertcat(*map(ca.vec, inputs[:-1])))
    rows = np.cumsum([0, *(o.numel() for o in outputs)])
    columns = np.cumsum([0, *(i.numel() for i in inputs[:-1])])
    blocks = [whole[int(rows[o]):int(rows[o + 1]), int(columns[i]):int(columns[i + 1])]
              for o in range(len(outputs)) for i in range(len(inputs) - 1)]
    return ca.Function(
        name or f"jac_{function.name()}", [*inputs[:-1], *nominal, inputs[-1]], blocks,
        [*names_in, *(f"out_{o}" for o in names_out), function.name_in()[-1]],
        [f"jac_{o}_{i}" for o in names_out for i in names_in])


def problem(dynamics: ca.Function, exact: bool = True,
            jacobian: ca.Function | None = None) -> dict:
    """casadi.integrator's problem over (t, x) -> ode or (t, x, z, p) -> (ode, alg), as MX
    (exact, jacobian: see forward_jacobian)."""
    function = forward_jacobian(dynamics, exact, jacobian)
    symbols = {name: ca.MX.sym(name, dynamics.sparsity_in(name)) for name in dynamics.name_in()}
    return symbols | function.call(symbols)
