"""backends.split: an SX Function cut into a chain of parts computes what the Function computes
(the same operations on the same operands), interpreted and compiled, and a changed toolchain
setting (a function's own flags) changes a library's cache key."""

import casadi as ca
import numpy as np

import casmech
from casmech.backends import codegen, library
from casmech.backends.split import joined, parts
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


def test_the_parts_in_turn_are_the_function():
    motion = joint_system(casmech.compile(casmech.load(MODELS / "double_pendulum.yaml"))).motion
    for function, count in ((_function(), 2), (_function(), 3), (motion, 2), (motion, 5)):
        chain = parts(function, [f"part{k}" for k in range(count)])
        assert len(chain) == count
        again = joined(chain, function.name())
        assert again.name_in() == function.name_in()
        assert again.name_out() == function.name_out()
        assert all(again.sparsity_out(k) == function.sparsity_out(k)
                   for k in range(function.n_out()))
        # part k takes the inputs and the earlier parts' shared values
        assert [part.n_in() for part in chain] == [function.n_in() + k for k in range(count)]
        # each part holds about its share of the work
        assert max(p.n_instructions() for p in chain) < function.n_instructions()
        for _ in range(3):
            arguments = _arguments(function)
            _assert_same(again(*arguments), function(*arguments))


def test_an_mx_function_is_not_split():
    x = ca.MX.sym("x", 2)
    assert parts(ca.Function("g", [x], [ca.sin(x) * x[0]]), ("head", "tail")) is None


def test_the_compiled_parts_are_the_function(toolchain, tmp_path):
    function = _function()
    names = ("f_0", "f_1", "f_2")
    built = codegen.compile_functions(dict(zip(names, parts(function, names), strict=True)),
                                      toolchain=toolchain, root=tmp_path)
    again = joined([built[name] for name in names], "f")
    arguments = _arguments(function)
    for a, b in zip(again(*arguments), function(*arguments), strict=True):
        # the same SX compiled to C: roundoff
        np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-12, atol=1e-12)


def test_a_functions_own_flags_are_in_the_key():
    functions = {"f": _function()}
    plain = codegen.Toolchain(flags=("-O1",))
    quick = codegen.Toolchain(flags=("-O1",), function_flags=(("f", ("-O0",)),))
    assert quick.flags_of("f") == ("-O0",) and quick.flags_of("g") == ("-O1",)
    keys = {library.content_key(functions, set(), set(), chain) for chain in (plain, quick)}
    assert len(keys) == 2
