"""The builder's two evaluations (equations.evaluation): the mapped bundle code generation compiles
(kernels mapped over their instances, each kernel's own derivatives) equals the inline bundle
(the kernels expanded into one SX graph, differentiated as a whole): values on random inputs,
names, sparsity, also over the model data d (model.parametric) at random d; and the mapped code
(with the DAE residuals of formulations.residuals, tested in test_residuals.py) does not grow
with the number of bodies."""


import functools

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.backends import codegen, generate
from casmech.equations import force_kernels, rows
from casmech.equations.functions import build_functions, mapped_functions
from casmech.model import parametric
from casmech.model.lower import lower
from tests.conftest import ROOT
from tests.helpers.codegen import MODEL

# Functions whose mapped pattern leaves out entries that are the constant 0 in the kernels
# (the inline functions list them: their AD of the whole graph, and a constant J_bar's zeros):
# a subset, equal in value (equations.rows.pattern).
SUBSET = {"variations", "romega_jacobian", "romega_mass"}


def chain_text(bodies: int) -> str:
    """N bars of 1 m along x, spherical joints at their ends (benchmarks/systems.py's chain)."""
    lines = ["casmech: 1", f"name: chain{bodies}", "bodies:"]
    lines += [f"  - {{name: b{k}, mass: 1.0, inertia: [1.0e-4, 0.0834, 0.0834], "
              f"position: [{k + 0.5}, 0, 0]}}" for k in range(bodies)]
    lines += ["joints:"]
    lines += [f"  - {{name: j{k}, type: spherical, body_i: {'ground' if k == 0 else f'b{k - 1}'}, "
              f"body_j: b{k}, at: [{k}, 0, 0]}}" for k in range(bodies)]
    return "\n".join(lines) + "\n"


MOTORS = """
casmech: 1
name: motors
bodies:
  - {name: bar, mass: 5, inertia: [2, 2, 0.01], position: [0, 0, -1]}
  - {name: disc, mass: 1, inertia: [0.15, 0.15, 0.25], position: [0, 0, -3]}
  - {name: block, mass: 2, inertia: [0.1, 0.1, 0.1], position: [1, 0, -3]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [1, 0, 0],
     driver: {angle: 0.3 * sin(t)}}
  - {name: spin, type: revolute, body_i: bar, body_j: disc, at: [0, 0, -3], axis: [0, 0, 1],
     motor: {torque: "2 - 0.1*angle - 0.3*angle_dot"}}
  - {name: slide, type: translational, body_i: disc, body_j: block, at: [1, 0, -3],
     axis: [1, 0, 0], motor: {force: "-3*displacement + sin(t) - 0.2*displacement_dot"}}
"""

MODELS = {
    "codegen_test": lambda: casmech.load(MODEL),  # driven revolute, tsda, body torque
    "chain4": lambda: casmech.loads(chain_text(4)),
    "slider_crank": lambda: casmech.load(ROOT / "models" / "slider_crank.yaml"),
    # effort motors (in the forces and the joints' reactions, laws reading the joint rate too),
    # laws reading joint and body state
    "motors": lambda: casmech.loads(MOTORS),
    # joint friction (a law by the rate's sign, its columns) beside motors and a driver
    "friction": lambda: casmech.loads(MOTORS.replace(
        "axis: [1, 0, 0], motor:", "axis: [1, 0, 0], friction: {coulomb: 0.5, viscous: 0.1},"
        " motor:").replace("axis: [0, 0, 1],", "axis: [0, 0, 1], friction: {coulomb: 0.2},")),
}  # and every model of models/ (EVERY_MODEL: rsda, point forces, user forces, contacts ...)


def _random(function: ca.Function, rng) -> list[ca.DM]:
    return [ca.DM(function.sparsity_in(k), rng.uniform(-1, 1, function.nnz_in(k)))
            for k in range(function.n_in())]


def _close(got: ca.DM, want: ca.DM, message: str) -> None:
    want = np.array(ca.DM(want).full())
    # the same algebra grouped differently (sums in another order): round-off only, relative
    # to the output's scale (measured <= 3e-16 of it; bushing-stiff residuals reach 1e5)
    np.testing.assert_allclose(np.array(ca.DM(got).full()), want, rtol=1e-12,
                               atol=1e-12 * max(1.0, np.max(np.abs(want), initial=0)),
                               err_msg=message)


def _triplets(sparsity: ca.Sparsity) -> set:
    return set(zip(*sparsity.get_triplet(), strict=True))


def _compare_bundles(got: dict, want: dict, seed: int = 3) -> None:
    rng = np.random.default_rng(seed)
    assert list(got) == list(want)
    for name, reference in want.items():
        function = got[name]
        assert function.name_in() == reference.name_in(), name
        assert function.name_out() == reference.name_out(), name
        for k in range(reference.n_out()):
            mine, theirs = function.sparsity_out(k), reference.sparsity_out(k)
            if name in SUBSET:
                assert mine.shape == theirs.shape and _triplets(mine) <= _triplets(theirs)
            else:
                assert mine == theirs, (name, reference.name_out(k))
        for _ in range(2):
            inputs = _random(reference, rng)
            for k, (a, b) in enumerate(zip(function.call(inputs), reference.call(inputs),
                                           strict=True)):
                _close(a, b, f"{name}.{reference.name_out(k)}")


def _inline(ir) -> dict:
    functions = build_functions(ir).functions
    return {name: functions[name] for name in functions}


@pytest.mark.parametrize("name", list(MODELS))
def test_mapped_functions_equal_inline(name):
    ir = lower(MODELS[name]())
    _compare_bundles(mapped_functions(ir), _inline(ir))


# every model of models/ (no C compiler: about a second each)
EVERY_MODEL = sorted(path.name for path in (ROOT / "models").glob("*.yaml"))


@functools.cache
def _every_model_inline(file: str) -> dict:
    """The numeric inline bundle of a model of models/, built once for the two tests below
    (CasADi Functions: evaluating them changes nothing)."""
    return _inline(lower(casmech.load(ROOT / "models" / file)))


@pytest.mark.parametrize("file", EVERY_MODEL)
def test_every_model_mapped_equals_inline(file):
    ir = lower(casmech.load(ROOT / "models" / file))
    _compare_bundles(mapped_functions(ir), _every_model_inline(file))


@pytest.mark.parametrize("file", EVERY_MODEL)
def test_every_model_over_its_data_mapped_equals_inline(file):
    """Both evaluations over the model data d (every number of the lowering an input) agree at
    random d too, and at the model's own d they are the numeric bundle."""
    ir = lower(casmech.load(ROOT / "models" / file))
    split = parametric.split(ir)
    inline = build_functions(split.ir, split.symbols).functions
    _compare_bundles(mapped_functions(split.ir, split.symbols),
                     {name: inline[name] for name in inline}, seed=11)
    numeric, rng = _every_model_inline(file), np.random.default_rng(5)
    for name, function in numeric.items():
        args = _random(function, rng)
        for a, b in zip(inline[name].call([*args, ca.DM(split.values)]), function.call(args),
                        strict=True):
            _close(a, b, f"{name} at the model's data")


def test_vectors_as_data_keep_values(monkeypatch):
    """Past BAKE_LIMIT geometries the rows' vectors are kernel inputs: the same values."""
    monkeypatch.setattr(rows, "BAKE_LIMIT", 0)
    model = MODELS["slider_crank"]()
    ir = lower(model)
    assert all(key.values is None for key in rows.row_keys(ir))
    got, want = mapped_functions(ir), _inline(ir)
    rng = np.random.default_rng(9)
    for name, reference in want.items():
        inputs = _random(reference, rng)
        for a, b in zip(got[name].call(inputs), reference.call(inputs), strict=True):
            _close(a, b, name)


def test_force_elements_without_a_kernel(monkeypatch):
    """Elements without a kernel (laws reading other joints' state, new element types) are
    built per instance from their laws: the same functions."""
    monkeypatch.setattr(force_kernels, "kernelised", lambda force: False)
    model = MODELS["codegen_test"]()
    got = mapped_functions(lower(model))
    want = _inline(lower(model))
    _compare_bundles({k: got[k] for k in ("generalized_forces", "energy", "romega_forces")},
                     {k: want[k] for k in ("generalized_forces", "energy", "romega_forces")})


def _code(bodies: int) -> list[str]:
    """The generated C of every function (with the Jacobians code generation adds), without
    the data: constant tables and the numbers in the code (sizes, offsets)."""
    ir = lower(casmech.loads(chain_text(bodies)))
    generator = ca.CodeGenerator("k.c", {"verbose": False})
    for group in generate.units(mapped_functions(ir)).values():
        for function in group:
            generator.add(function)
    for oracle in codegen.dae_oracles(ir).values():  # the DAE residuals (formulations.residuals)
        for function in oracle.values():
            generator.add(function)
    lines, table = [], False
    for line in generator.dump().splitlines():
        table = table or line.startswith("static const casadi_")
        if not table:
            lines.append("".join(c for c in line if not c.isdigit()))
        table = table and not line.rstrip().endswith(";")
    return lines


def test_code_does_not_grow_with_the_chain():
    """6 and 24 bodies: the same code but for a few declarations wrapped differently (casadi
    lays out work vectors by size); only the numbers and tables grow. (The unrolled code grows
    with every body.)"""
    small, large = _code(6), _code(24)
    assert len(small) > 1000 and abs(len(large) - len(small)) <= 0.001 * len(small)
