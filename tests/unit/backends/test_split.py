"""backends.split: an SX Function cut into a head and a tail computes what the Function
computes (the same operations on the same operands), interpreted and compiled, and a changed
toolchain setting (a function's own flags) changes a library's cache key."""

import casadi as ca
import numpy as np

import casmech
from casmech.backends import codegen, library
from casmech.backends.split import halves, joined
from casmech.runtime.joint_dynamics import joint_system
from tests.conftest import MODELS

RNG = np.random.default_rng(7)


def _function() -> ca.Function:
    """Unary and binary operations, constants, a sparse output, an output assigned early."""
    x, y = ca.SX.sym("x", 3), ca.SX.sym("y", 2)
    a = ca.sin(x[0]) * y[1] + 2.5 * ca.exp(-x[1] ** 2)
    b = ca.atan2(a, 1 + x[2] ** 2) - ca.sqrt(1 + y[0] ** 2) * a
    sparse = ca.SX(ca.Sparsity.lower(2), ca.vertcat(b, a * b, ca.cos(b)))
    return ca.Function("f", [x, y], [x[0] * 2, sparse, ca.vertcat(a, b, a + b)],
                       ["x", "y"], ["early", "sparse", "late"])


def _arguments(function: ca.Function) -> list[np.ndarray]:
    return [RNG.uniform(-1, 1, function.sparsity_in(k).shape) for k in range(function.n_in())]


def _assert_same(got, want) -> None:
    for a, b in zip(got, want, strict=True):
        # the same operations on the same operands in the same order: equal bit for bit, but
        # for a rebuilt node CasADi might simplify
        np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-14, atol=1e-14)


def test_head_then_tail_is_the_function():
    motion = joint_system(casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))).motion
    for function in (_function(), motion):
        head, tail = halves(function, "head", "tail")
        both = joined(head, tail, function.name())
        assert both.name_in() == function.name_in() and both.name_out() == function.name_out()
        assert all(both.sparsity_out(k) == function.sparsity_out(k)
                   for k in range(function.n_out()))
        # each half holds about half of the work
        assert max(head.n_instructions(), tail.n_instructions()) < function.n_instructions()
        for _ in range(3):
            arguments = _arguments(function)
            _assert_same(both(*arguments), function(*arguments))


def test_an_mx_function_is_not_split():
    x = ca.MX.sym("x", 2)
    assert halves(ca.Function("g", [x], [ca.sin(x) * x[0]]), "head", "tail") is None


def test_the_compiled_halves_are_the_function(toolchain, tmp_path):
    function = _function()
    head, tail = halves(function, "f_head", "f_tail")
    built = codegen.compile_functions({"f_head": head, "f_tail": tail}, toolchain=toolchain,
                                      root=tmp_path)
    both = joined(built["f_head"], built["f_tail"], "f")
    arguments = _arguments(function)
    for a, b in zip(both(*arguments), function(*arguments), strict=True):
        # the same SX compiled to C: roundoff
        np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-12, atol=1e-12)


def test_a_functions_own_flags_are_in_the_key():
    functions = {"f": _function()}
    plain = codegen.Toolchain(flags=("-O1",))
    quick = codegen.Toolchain(flags=("-O1",), function_flags=(("f", ("-O0",)),))
    assert quick.flags_of("f") == ("-O0",) and quick.flags_of("g") == ("-O1",)
    keys = {library.content_key(functions, set(), set(), chain) for chain in (plain, quick)}
    assert len(keys) == 2
