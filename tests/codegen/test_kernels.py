"""Kernel-mapped constraint functions equal the unrolled SX ones (compiler.assemble): values on
random inputs (drivers included: the test model's driven revolute exercises the Taylor
coefficients of f(t)), and Phi_q's structure contains the SX pattern."""

import sys
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.codegen import kernels
from casmech.compiler.lower import lower

from .conftest import MODEL

ROOT = Path(__file__).resolve().parents[2]


def _models():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import casmech_model
    import systems
    return {"codegen_test": casmech.load(MODEL),
            "chain4": casmech.loads(casmech_model.yaml_text(systems.make("chain4"))),
            "slider_crank": casmech.load(ROOT / "models" / "slider_crank.yaml")}


@pytest.mark.parametrize("name", ["codegen_test", "chain4", "slider_crank"])
def test_kernel_functions_equal_unrolled(name):
    model = _models()[name]
    mapped, unrolled = kernels.constraint_functions(lower(model)), casmech.compile(model)
    rng = np.random.default_rng(3)
    n = unrolled.n_coordinates
    for t, q, q_dot in [(rng.uniform(0, 2), rng.uniform(-1, 1, n), rng.uniform(-1, 1, n))
                        for _ in range(3)]:
        for function, args in (("phi", (t, q)), ("phi_q", (t, q)), ("nu", (t, q)),
                               ("gamma", (t, q, q_dot))):
            assert mapped[function].name_in() == unrolled[function].name_in()
            got, want = mapped[function](*args), unrolled[function](*args)
            # the same algebra, grouped differently: round-off only (measured <= 2e-16)
            np.testing.assert_allclose(got.full(), want.full(), rtol=1e-12, atol=1e-12,
                                       err_msg=f"{name} {function}")
    pattern, reference = (f["phi_q"].sparsity_out(0) for f in (mapped, unrolled))
    assert set(zip(*reference.get_triplet(), strict=True)) <= set(
        zip(*pattern.get_triplet(), strict=True))


def test_kernel_code_does_not_grow_with_the_chain():
    """The generated C for 4 and 16 bodies holds the same kernels; only index tables grow
    (the unrolled code grows with every joint)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import casmech_model
    import systems

    def kernel_names(bodies):
        ir = lower(casmech.loads(casmech_model.yaml_text(systems.make(f"chain{bodies}"))))
        code = ca.CodeGenerator("k.c")
        for function in kernels.constraint_functions(ir).values():
            code.add(function)
        return {line.split("(")[0].split()[-1] for line in code.dump().splitlines()
                if line.startswith("static int casadi_f")}

    assert kernel_names(4) == kernel_names(16)
