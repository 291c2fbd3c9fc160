"""Every model in models/: its compiled libraries (the parametric one where the model has
parameters, and the mapped one with the values built in) equal the interpreted bundle, every
system function and every DAE residual, at random inputs (issue 15: interpreted == compiled ==
parametric on every model)."""

import numpy as np
import pytest

import casmech
from casmech.backends import codegen, parametric
from casmech.formulations import dae
from casmech.formulations.table import FORMULATIONS
from tests.conftest import MODELS

NAMES = sorted(p.name for p in MODELS.glob("*.yaml"))


def _close(got, want, message: str) -> None:
    got, want = np.asarray(got, float), np.asarray(want, float)
    # the same SX expressions in C (or mapped kernels) against casadi's virtual machine:
    # round-off, relative to the output's largest entry (stiff contacts reach 1e5)
    np.testing.assert_allclose(got, want, rtol=1e-12,
                               atol=1e-12 * (1 + np.max(np.abs(want), initial=0)),
                               err_msg=message)


def _libraries(model) -> list[bool]:
    return [True, False] if parametric.applies(model) else [False]


@pytest.mark.slow  # C for every model: ~2 min on 2 cores
@pytest.mark.parametrize("name", NAMES)
def test_compiled_equals_interpreted(name, toolchain, cache_root):
    model = casmech.load(MODELS / name)
    plain = casmech.compile(model, "interpreted")
    rng = np.random.default_rng(sum(map(ord, name)))
    for library in _libraries(model):
        bound = codegen.compiled(model, toolchain, root=cache_root, parametric_library=library)
        assert codegen.mode_of(bound) == "compiled"
        assert set(plain.functions) <= set(bound.functions)
        for function_name, function in plain.functions.items():
            args = [rng.standard_normal(function.sparsity_in(k).shape)
                    for k in range(function.n_in())]
            for k, (got, want) in enumerate(zip(bound.evaluate(function_name, *args),
                                                plain.evaluate(function_name, *args),
                                                strict=True)):
                _close(got, want, f"{name} {library=} {function_name}.{function.name_out(k)}")
        _compare_residuals(name, library, bound, plain, rng)


def _compare_residuals(name: str, library: bool, bound, plain, rng) -> None:
    """Each DAE residual of the library (data appended to p in the parametric one) against
    formulations.dae's over the interpreted bundle: the ode and alg outputs."""
    data = np.zeros(0) if bound.data is None else np.asarray(bound.data, float)
    for form in FORMULATIONS:
        for kind in dae.STABILIZATIONS:
            want = dae.residual(plain.functions, form, kind)
            residual_name = want.name()
            if residual_name not in bound.functions:
                continue  # a library without DAEs (kinematic analyses)
            args = [rng.standard_normal(want.sparsity_in(k).shape) for k in range(4)]
            got = bound[residual_name](*args[:3], np.concatenate([args[3].ravel(), data]), [])
            for k, (g, w) in enumerate(zip(got[:2], want(*args), strict=True)):
                _close(np.array(g), np.array(w), f"{name} {library=} {residual_name} out {k}")
