"""The r-p bundle's per-primitive, per-body and per-joint terms built through traced steps
(equations/assemble.py constraint rows and frames, equations/eom.py energy and reactions,
equations/body.py RATES; core/traced_steps.py) against the same code run directly on the SX
(traced.direct()): no more instructions, the same values at random inputs."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.core import traced_steps as traced
from casmech.equations.functions import build_functions
from casmech.model.lower import lower
from tests.compiler.test_joint_system import ZOO, chain_text
from tests.conftest import MODELS

CASES = {"four_bar": lambda: casmech.load(MODELS / "four_bar.yaml"),  # a driver: phi_scaled
         "chain8": lambda: casmech.loads(chain_text(8)),
         "zoo": lambda: casmech.load(ZOO)}
NAMES = ("phi", "phi_q", "nu", "gamma", "variations", "phi_scaled", "reactions", "energy",
         "body_rates")


def bundle(model) -> dict[str, ca.Function]:
    functions = build_functions(lower(model)).functions
    return {name: functions[name] for name in NAMES}  # built now (the bundle is lazy)


@pytest.mark.parametrize("case", CASES)
def test_traced_terms_equal_the_terms_run_directly(case):
    model = CASES[case]()
    with traced.direct():
        direct = bundle(model)
    steps = bundle(model)
    rng = np.random.default_rng(5)
    for name in NAMES:
        want_f, got_f = direct[name], steps[name]
        assert got_f.n_instructions() <= want_f.n_instructions(), name
        for _ in range(3):
            args = [rng.uniform(-1, 1, want_f.sparsity_in(k).shape) for k in range(want_f.n_in())]
            got, want = got_f.call(args), want_f.call(args)
            for a, b in zip(got, want, strict=True):
                b = np.array(b.full())
                scale = max(1.0, float(np.max(np.abs(b), initial=0.0)))
                # the same operations but for the association of products of constants
                # (folded when a step is evaluated): round-off of the largest entry
                np.testing.assert_allclose(np.array(a.full()), b, rtol=1e-12,
                                           atol=1e-12 * scale, err_msg=name)
