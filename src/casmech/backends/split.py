"""One SX Function as a chain of parts, computed one after the other: for C compiled in units at
once (gcc's time on a function grows faster than the function, and two cores compile parts
side by side), and evaluated part by part over many rows (backends.rows_loop: each part's
machine code stays in the instruction cache over the rows, where the whole function's would
not).

    first, second, last = parts(f, ("f_0", "f_1", "f_2"))   # SX Functions
    f_again = joined((first, second, last), f.name())        # MX: f's inputs and outputs

The cuts fall at equal shares of f's algorithm (its instruction list). Part k takes f's inputs
and the values every earlier part shares (`shared_0`, ..., `shared_<k-1>`) and computes its
share of the algorithm; a part but the last returns, as `shared_<k>`, every value of its own
that a later part reads (f's outputs it assigns included; not inputs and constants, which every
part has); the last part returns f's outputs. Each instruction is rebuilt with the same
operation on the same operands, so the chain computes what f computes, in the same order.
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca

_UNSPLIT = (ca.OP_CALL,)  # operations not rebuilt from their operands alone


def parts(function: ca.Function, names: Sequence[str]) -> tuple[ca.Function, ...] | None:
    """The chain of len(names) parts of an SXFunction (module docstring), or None for another
    kind of Function or when its algorithm holds an operation this cannot rebuild."""
    if not function.is_a("SXFunction"):
        return None
    count = function.n_instructions()
    operations = [function.instruction_id(k) for k in range(count)]
    if any(op in _UNSPLIT for op in operations):
        return None
    inputs = function.sx_in()
    entries = [[x.nz[j] for j in range(x.nnz())] for x in inputs]
    n, last = len(names), len(names) - 1
    ends = [count * (k + 1) // n for k in range(n)]  # part k: instructions before ends[k]
    written: dict[int, tuple[int, int, ca.SX]] = {}  # work index -> (part, instruction, value)
    # per part: its instruction -> (its value, the symbol later parts read it by)
    shared: list[dict[int, tuple[ca.SX, ca.SX]]] = [{} for _ in names]
    outputs = [[ca.SX(0)] * function.nnz_out(o) for o in range(function.n_out())]

    def value(index: int, part: int) -> ca.SX:
        own, made, found = written[index]
        if own == part or operations[made] in (ca.OP_INPUT, ca.OP_CONST):
            return found  # its own, or an input or constant every part has
        if made not in shared[own]:
            shared[own][made] = (found, ca.SX.sym(f"shared_{own}_{len(shared[own])}"))
        return shared[own][made][1]

    part = 0
    for k, op in enumerate(operations):
        while k >= ends[part]:
            part += 1
        if op == ca.OP_OUTPUT:
            (index,), (o, nz) = function.instruction_input(k), function.instruction_output(k)
            outputs[o][nz] = value(index, last)  # through the last part
            continue
        if op == ca.OP_INPUT:
            i, nz = function.instruction_input(k)
            result = entries[i][nz]
        elif op == ca.OP_CONST:
            result = ca.SX(function.instruction_constant(k))
        else:
            operands = [value(index, part) for index in function.instruction_input(k)]
            result = (ca.SX.unary(op, operands[0]) if len(operands) == 1
                      else ca.SX.binary(op, *operands))
        (index,) = function.instruction_output(k)
        written[index] = (part, k, result)
    links = [[values[m] for m in sorted(values)] for values in shared]
    chain = []
    for k, name in enumerate(names):
        link_in = [ca.vertcat(ca.SX(0, 1), *(symbol for _, symbol in links[j])) for j in range(k)]
        names_in = [*function.name_in(), *(f"shared_{j}" for j in range(k))]
        if k < last:
            chain.append(ca.Function(name, [*inputs, *link_in],
                                     [ca.vertcat(ca.SX(0, 1), *(v for v, _ in links[k]))],
                                     names_in, [f"shared_{k}"]))
            continue
        chain.append(ca.Function(
            name, [*inputs, *link_in],
            [ca.SX(function.sparsity_out(o), ca.vertcat(*column)) if column else
             ca.SX(function.sparsity_out(o)) for o, column in enumerate(outputs)],
            names_in, function.name_out()))
    return tuple(chain)


def joined(chain: Sequence[ca.Function], name: str) -> ca.Function:
    """The chain's parts called in turn as an MX Function `name` with the first part's f
    inputs and the last part's outputs (the parts' compiled externals stay compiled)."""
    first = chain[0]
    inputs = [ca.MX.sym(first.name_in(k), first.sparsity_in(k)) for k in range(first.n_in())]
    links: list[ca.MX] = []
    for part in chain[:-1]:
        links.append(part.call([*inputs, *links])[0])
    outputs = chain[-1].call([*inputs, *links])
    return ca.Function(name, inputs, outputs, first.name_in(), chain[-1].name_out())
