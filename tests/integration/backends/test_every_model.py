"""Every model in models/: its compiled libraries (the parametric one where the model has
parameters, and the mapped one with the values built in) equal the interpreted bundle, every
system function and every DAE residual, at random inputs; the parametric library and both
evaluations of the builder over the model data (inline, mapped) agree at random model data d
too (issue 30: interpreted == compiled == mapped == parametric at random (t, q, v, d))."""

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.backends import codegen, parametric
from casmech.backends.load import externals
from casmech.equations.functions import build_functions, mapped_functions
from casmech.formulations import dae
from casmech.formulations.table import BODY_FORMS
from casmech.model import parametric as model_data
from casmech.model.lower import lower
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
    if parametric.applies(model):
        _compare_over_data(name, model, toolchain, cache_root, rng)


def _compare_over_data(name: str, model, toolchain, cache_root, rng) -> None:
    """The parametric library's own functions (the model data d their last input) against the
    inline and the mapped bundle over d, at d moved at random from the model's (each entry by up
    to 20 %, signs and zeros kept), and its DAE residuals (d after p) against formulations.dae's
    over the inline bundle."""
    ir = lower(model)
    split = model_data.split(ir)
    directory = cache_root / parametric.key(model, split.signature, toolchain, True)
    library = externals(directory)
    inline = build_functions(split.ir, split.symbols).functions
    mapped = mapped_functions(split.ir, split.symbols)
    d = split.values * (1 + 0.2 * rng.uniform(-1, 1, split.values.size))
    for function_name, function in mapped.items():
        args = [rng.standard_normal(function.sparsity_in(k).shape)
                for k in range(function.n_in() - 1)]
        want = [np.array(o.full()) for o in inline[function_name].call([*args, d])]
        for label, got in (("library", library[function_name].call([*args, d])),
                           ("mapped", function.call([*args, d]))):
            for k, (g, w) in enumerate(zip(got, want, strict=True)):
                _close(np.array(ca.DM(g).full()), w,
                       f"{name} {label} over d: {function_name}.{function.name_out(k)}")
    for form in BODY_FORMS:
        for kind in dae.STABILIZATIONS:
            want = dae.residual(inline, form, kind)
            if want.name() not in library:
                continue
            args = [rng.standard_normal(want.sparsity_in(k).shape) for k in range(4)]
            p = np.concatenate([args[3].ravel()[:want.size1_in(3) - d.size], d])
            got = library[want.name()](*args[:3], p, [])
            for k, (g, w) in enumerate(zip(got[:2], want(*args[:3], p), strict=False)):
                _close(np.array(g), np.array(w), f"{name} over d: {want.name()} out {k}")


def _compare_residuals(name: str, library: bool, bound, plain, rng) -> None:
    """Each DAE residual of the library (data appended to p in the parametric one) against
    formulations.dae's over the interpreted bundle: the ode and alg outputs."""
    data = np.zeros(0) if bound.data is None else np.asarray(bound.data, float)
    for form in BODY_FORMS:
        for kind in dae.STABILIZATIONS:
            want = dae.residual(plain.functions, form, kind)
            residual_name = want.name()
            if residual_name not in bound.functions:
                continue  # a library without DAEs (kinematic analyses)
            args = [rng.standard_normal(want.sparsity_in(k).shape) for k in range(4)]
            got = bound[residual_name](*args[:3], np.concatenate([args[3].ravel(), data]), [])
            for k, (g, w) in enumerate(zip(got[:2], want(*args), strict=True)):
                _close(np.array(g), np.array(w), f"{name} {library=} {residual_name} out {k}")
