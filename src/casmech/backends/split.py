"""One SX Function as two, head then tail, for C compiled in two units at once: gcc's time on
a function grows faster than the function, and two cores compile the halves side by side.

    head, tail = halves(f, "f_head", "f_tail")   # SX Functions
    f_again = joined(head, tail, f)              # MX: tail(inputs, head(inputs)), f's names

The cut falls at the middle of f's algorithm (its instruction list): the head computes the first
half and returns every value of it the second half reads (and f's outputs it assigns); the tail
takes f's inputs and those values and computes the rest with f's outputs. Each instruction is
rebuilt with the same operation on the same operands, so the pair computes what f computes, in
the same order.
"""

from __future__ import annotations

import casadi as ca

_UNSPLIT = (ca.OP_CALL,)  # operations not rebuilt from their operands alone


def halves(function: ca.Function, head_name: str, tail_name: str
           ) -> tuple[ca.Function, ca.Function] | None:
    """(head, tail) of an SXFunction (module docstring), or None for another kind of Function
    or when its algorithm holds an operation this cannot rebuild."""
    if not function.is_a("SXFunction"):
        return None
    count = function.n_instructions()
    operations = [function.instruction_id(k) for k in range(count)]
    if any(op in _UNSPLIT for op in operations):
        return None
    inputs = function.sx_in()
    entries = [[x.nz[j] for j in range(x.nnz())] for x in inputs]
    cut = count // 2
    head: dict[int, tuple[int, ca.SX]] = {}  # work index -> (instruction, value) of the head
    tail: dict[int, ca.SX] = {}  # work index -> value, once the tail wrote it
    shared: dict[int, tuple[ca.SX, ca.SX]] = {}  # head instruction -> (value, tail's symbol)
    outputs = [[ca.SX(0)] * function.nnz_out(o) for o in range(function.n_out())]

    def value(index: int, k: int) -> ca.SX:
        if k < cut:
            return head[index][1]
        if index in tail:
            return tail[index]
        made, found = head[index]
        if made not in shared:
            shared[made] = (found, ca.SX.sym(f"shared_{len(shared)}"))
        return shared[made][1]

    for k, op in enumerate(operations):
        if op == ca.OP_OUTPUT:
            (index,), (o, nz) = function.instruction_input(k), function.instruction_output(k)
            outputs[o][nz] = value(index, max(k, cut))  # through the tail
            continue
        if op == ca.OP_INPUT:
            i, nz = function.instruction_input(k)
            result = entries[i][nz]
        elif op == ca.OP_CONST:
            result = ca.SX(function.instruction_constant(k))
        else:
            operands = [value(index, k) for index in function.instruction_input(k)]
            result = (ca.SX.unary(op, operands[0]) if len(operands) == 1
                      else ca.SX.binary(op, *operands))
        (index,) = function.instruction_output(k)
        if k < cut:
            head[index] = (k, result)
        else:
            tail[index] = result
    values = [shared[k] for k in sorted(shared)]
    link = ca.vertcat(*(symbol for _, symbol in values))
    head_function = ca.Function(head_name, inputs, [ca.vertcat(*(v for v, _ in values))],
                                function.name_in(), ["shared"])
    tail_function = ca.Function(
        tail_name, [*inputs, link],
        [ca.SX(function.sparsity_out(o), ca.vertcat(*column)) if column else
         ca.SX(function.sparsity_out(o)) for o, column in enumerate(outputs)],
        [*function.name_in(), "shared"], function.name_out())
    return head_function, tail_function


def joined(head: ca.Function, tail: ca.Function, name: str) -> ca.Function:
    """tail(inputs, head(inputs)) as an MX Function `name` with the tail's output names and
    the head's inputs (the pair's compiled externals stay compiled)."""
    inputs = [ca.MX.sym(head.name_in(k), head.sparsity_in(k)) for k in range(head.n_in())]
    outputs = tail.call([*inputs, *head.call(inputs)])
    return ca.Function(name, inputs, outputs, head.name_in(), tail.name_out())
