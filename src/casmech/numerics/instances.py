"""A kernel evaluated over its instances, inline or mapped: the switch every builder of
casmech's system functions goes through.

A kernel is a small SX Function of one instance (a constraint row, a body, a force element, a
joint's rows, an element of a DAE residual); an argument holds every instance's value side by
side (column block k: instance k), or one value that all instances share.

- inline: each instance's kernel is evaluated on its SX arguments, which expands it into the
  caller's graph (no call node; CasADi folds operations on constants and drops x * 0, x + 0
  and x * 1): one SX graph, which a Function built with common subexpressions merged (`cse`)
  evaluates fastest in CasADi's virtual machine and compiles to straight-line C.
- mapped: one MX call of the kernel through casadi's map, a loop in C over the instances: code
  whose size does not grow with the number of instances.
"""

from __future__ import annotations

import casadi as ca

# Derivative directions per call of a mapped kernel's derivative. casadi batches up to 64 by
# default: code 64 times the kernel's derivative; 1 gives less C, built sooner
# (docs/decisions/codegen-flags.md).
MAX_DIRECTIONS = 1


def mapped(kernel: ca.Function, count: int) -> ca.Function:
    """The kernel evaluated over `count` instances (columns), serially, named after it."""
    return kernel.map(f"map{count}_{kernel.name()}", "serial", count, [], [],
                      {"max_num_dir": MAX_DIRECTIONS})


def plain_map(kernel: ca.Function, count: int) -> ca.Function:
    """The kernel over `count` instances, serially, with casadi's default name and options (the
    element sums of a DAE residual)."""
    return kernel.map(count, "serial")


def _side_by_side(kernel: ca.Function, k: int, arg, count: int) -> ca.SX:
    """The kernel's input k for `count` instances side by side: `arg` itself, or repeated
    when it is one instance wide."""
    arg = ca.SX(arg) if not isinstance(arg, ca.SX) else arg
    return ca.repmat(arg, 1, count) if arg.size2() == kernel.size2_in(k) and count > 1 else arg


def inline(kernel: ca.Function, count: int, args) -> list[ca.SX]:
    """The kernel's outputs over `count` instances, side by side, each instance's kernel
    expanded into SX: one evaluation of the kernel mapped over the instances on SX, which
    expands every instance as its own call would, in one call from Python."""
    if not count:
        return [ca.SX(kernel.size1_out(o), 0) for o in range(kernel.n_out())]
    function = kernel if count == 1 else plain_map(kernel, count)
    return function.call([_side_by_side(kernel, k, arg, count) for k, arg in enumerate(args)])


def over(kernel: ca.Function, count: int, args, is_inline: bool, map_with=mapped) -> list:
    """The kernel's outputs over `count` instances: inline (SX) or through `map_with` (MX)."""
    if is_inline:
        return inline(kernel, count, args)
    outputs = map_with(kernel, count)(*args)
    return list(outputs) if isinstance(outputs, tuple) else [outputs]
