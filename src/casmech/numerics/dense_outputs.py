"""A CasADi Function with its outputs dense: what C that reads and writes plain arrays takes
(runtime.buffers' buffers, an FMU's generated code, a compiled joint space); a sparse output's
structural zeros become stored zeros."""

from __future__ import annotations

import casadi as ca


def dense_outputs(function: ca.Function) -> ca.Function:
    """`function` with every output dense, under its name and its inputs' and outputs' names
    (itself where they are dense already)."""
    if all(function.sparsity_out(k).is_dense() for k in range(function.n_out())):
        return function
    inputs = function.sx_in() if function.is_a("SXFunction") else function.mx_in()
    return ca.Function(function.name(), inputs,
                       [ca.densify(out) for out in function.call(inputs)],
                       function.name_in(), function.name_out())
