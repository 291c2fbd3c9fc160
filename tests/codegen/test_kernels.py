"""Kernel-mapped constraint functions equal the unrolled SX ones (compiler.assemble): values on
random inputs (drivers included: the test model's driven revolute exercises the Taylor
coefficients of f(t)), and Phi_q's structure contains the SX pattern."""

from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.codegen import kernels
from casmech.compiler.lower import lower

from .conftest import MODEL

ROOT = Path(__file__).resolve().parents[2]


def chain_text(bodies: int) -> str:
    """N bars of 1 m along x, spherical joints at their ends (benchmarks/systems.py's chain)."""
    lines = ["casmech: 1", f"name: chain{bodies}", "bodies:"]
    lines += [f"  - {{name: b{k}, mass: 1.0, inertia: [1.0e-4, 0.0834, 0.0834], "
              f"position: [{k + 0.5}, 0, 0]}}" for k in range(bodies)]
    lines += ["joints:"]
    lines += [f"  - {{name: j{k}, type: spherical, body_i: {'ground' if k == 0 else f'b{k - 1}'}, "
              f"body_j: b{k}, at: [{k}, 0, 0]}}" for k in range(bodies)]
    return "\n".join(lines) + "\n"


def _models():
    return {"codegen_test": casmech.load(MODEL), "chain4": casmech.loads(chain_text(4)),
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

    def kernel_names(bodies):
        code = ca.CodeGenerator("k.c")
        for function in kernels.constraint_functions(lower(casmech.loads(chain_text(bodies))))\
                .values():
            code.add(function)
        return {line.split("(")[0].split()[-1] for line in code.dump().splitlines()
                if line.startswith("static int casadi_f")}

    assert len(kernel_names(4)) > 0 and kernel_names(4) == kernel_names(16)
