"""A Function whose Jacobian CasADi builds cheaply: forward sweeps mapped over the columns.

SUNDIALS integrators created through casadi.integrator build the Jacobian of their right-hand
side when they are constructed, even when they never evaluate it (CVODES's Adams method with
functional iteration). By symbolic differentiation of the articulated-body ODE that took 12 s
for a 32-body chain (a Jacobian of 14 million SX instructions). `forward_jacobian` gives the
function a custom Jacobian made of one forward-mode derivative mapped over the unit seeds:
built in about the time of that one derivative, exact to roundoff, evaluated in n forward
sweeps when a Newton iteration needs it.
"""

from __future__ import annotations

import casadi as ca


def forward_jacobian(function: ca.Function) -> ca.Function:
    """`function` (one output) with the custom Jacobian of the module docstring."""
    inputs = [ca.MX.sym(function.name_in(k), function.sparsity_in(k))
              for k in range(function.n_in())]
    output = ca.MX.sym(function.name_out(0), function.sparsity_out(0))
    sweep = function.forward(1)
    zeros = [ca.MX.zeros(function.sparsity_in(k).shape) for k in range(function.n_in())]
    blocks = []
    for k, x in enumerate(inputs):
        n = x.numel()
        seeds = [ca.repmat(z, 1, n) for z in zeros]
        seeds[k] = ca.MX.eye(n)
        blocks.append(sweep.map(n)(*inputs, output, *seeds))
    name = function.name_out(0)
    jacobian = ca.Function(
        f"jac_{function.name()}", [*inputs, output], blocks,
        [*function.name_in(), name], [f"jac_{name}_{i}" for i in function.name_in()])
    symbols = function.mx_in()  # MX: a call of `function` itself (compiled code stays so)
    return ca.Function(function.name(), symbols, function.call(symbols), function.name_in(),
                       function.name_out(), {"custom_jacobian": jacobian, "jac_penalty": 0})


def problem(ode: ca.Function) -> dict:
    """casadi.integrator's ODE dictionary over an (t, x) -> ode Function, called as MX."""
    t, x = ca.MX.sym("t"), ca.MX.sym("x", ode.sparsity_in(1))
    return {"t": t, "x": x, "ode": forward_jacobian(ode)(t, x)}
