"""The compiled bundle is the interpreted one: same functions, names, sparsity, values on random
inputs, and the same Jacobians through the generated jac_<name> or fwd1_/adj1_<name> (what an
MX graph over the library, such as the augmented-Lagrangian ODE, differentiates)."""

import casadi as ca
import numpy as np
import pytest

from casmech import codegen
from casmech.codegen import generate, manifest, mapped
from casmech.compiler.lower import lower

from .test_mapped import SUBSET

# the residuals a compiled bundle carries besides the interpreted functions (compiler.dae)
RESIDUALS = ["dae_ggl_rp", "dae_rp", "dae_ggl_romega", "dae_romega"]


def _random_inputs(function: ca.Function, rng) -> list[ca.DM]:
    return [ca.DM(function.sparsity_in(k), rng.uniform(-1, 1, function.nnz_in(k)))
            for k in range(function.n_in())]


def test_library_built_with_warnings_as_errors(build_dir):
    """The session build used -Wall -Werror (a warning would have failed it) and the manifest
    says so."""
    info = manifest.read(build_dir)
    assert {"-Wall", "-Werror"} <= set(info["flags"])
    assert (build_dir / info["library"]).is_file() and (build_dir / info["header"]).is_file()


def test_same_functions_names_and_sparsity(compiled, interpreted):
    """Same names, inputs and sparsity; the outputs of SUBSET leave out entries that are the
    constant 0 (test_mapped), so their patterns are contained in the interpreted ones."""
    assert codegen.mode_of(compiled) == "compiled"
    assert codegen.mode_of(interpreted) == "interpreted"
    # the compiled bundle carries the DAE residuals as well (compiler.dae uses them)
    assert list(compiled.functions) == [*interpreted.functions, *RESIDUALS]
    for name, expected in interpreted.functions.items():
        got = compiled[name]
        assert got.name() == name
        assert got.name_in() == expected.name_in() and got.name_out() == expected.name_out()
        for k in range(expected.n_in()):
            assert got.sparsity_in(k) == expected.sparsity_in(k), (name, k)
        for k in range(expected.n_out()):
            mine, theirs = got.sparsity_out(k), expected.sparsity_out(k)
            if name in SUBSET:
                assert mine.shape == theirs.shape and mine.is_subset(theirs), (name, k)
            else:
                assert mine == theirs, (name, k)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_values_equal_on_random_inputs(compiled, interpreted, seed):
    rng = np.random.default_rng(seed)
    for name, expected in interpreted.functions.items():
        inputs = _random_inputs(expected, rng)
        for got, want in zip(compiled[name].call(inputs), expected.call(inputs), strict=True):
            # the same equations, built from mapped kernels (sums grouped differently): the
            # issue's bound; measured differences <= 4e-16
            np.testing.assert_allclose(got.full(), want.full(), rtol=1e-12, atol=1e-12,
                                       err_msg=name)


def test_jacobians_through_the_library_equal_ad(compiled, interpreted):
    """jac_<name> from the library (used when an MX graph over the bundle is differentiated)
    equals CasADi's AD of the interpreted function."""
    rng = np.random.default_rng(7)
    # matrix functions through fwd1_/adj1_<name> (generate.DIRECTIONAL), the others jac_<name>
    for name in sorted(generate.DIFFERENTIATED | generate.DIRECTIONAL):
        symbols = [ca.MX.sym(n, interpreted[name].sparsity_in(k))
                   for k, n in enumerate(interpreted[name].name_in())]
        values = _random_inputs(interpreted[name], rng)
        for k in range(interpreted[name].n_out()):
            jacobians = [ca.Function("j", symbols, [ca.jacobian(bundle[name].call(symbols)[k],
                                                                ca.vcat(symbols))])
                         for bundle in (compiled, interpreted)]
            got, want = (f.call(values)[0].full() for f in jacobians)
            # same operations in both; 1e-12 is the compiled-vs-interpreted bound
            np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12, err_msg=name)


def test_manifest_describes_every_function(build_dir, interpreted, model):
    """Names, sizes and sparsity in manifest.json rebuild the functions' own patterns (those
    code generation compiled: codegen.mapped); the exported library also holds the DAE
    residuals."""
    entries = {e["name"]: e for e in manifest.read(build_dir)["functions"]}
    built = mapped.mapped_functions(lower(model), residuals=True)
    residuals = {name: f for name, f in built.items() if name.startswith("dae_")}
    assert set(entries) == set(built) == {*interpreted.functions, *RESIDUALS}
    for name, function in built.items():
        entry = entries[name]
        assert [i["name"] for i in entry["inputs"]] == function.name_in()
        assert [o["name"] for o in entry["outputs"]] == function.name_out()
        for k, output in enumerate(entry["outputs"]):
            assert manifest.sparsity(output) == function.sparsity_out(k)
        assert entry["jacobian"] == (name in generate.DIFFERENTIATED or name in residuals)
        assert entry["forward_reverse"] == (name in generate.DIRECTIONAL)


def test_dae_residuals_and_jacobians_equal_interpreted(compiled, interpreted):
    """The DAE residuals (both stabilizations, both formulations) of the compiled bundle (what
    IDAS integrates) and their Jacobians equal compiler.dae over the interpreted bundle."""
    library = compiled.functions
    rng = np.random.default_rng(11)
    for name, want in generate.dae_functions(interpreted.functions).items():
        got = library[name]
        assert got.name_in() == want.name_in() and got.name_out() == want.name_out()
        inputs = _random_inputs(want, rng)
        for a, b in zip(got.call(inputs), want.call(inputs), strict=True):
            # same operations: the compiled-vs-interpreted bound
            np.testing.assert_allclose(a.full(), b.full(), rtol=1e-12, atol=1e-12)
        symbols = [ca.MX.sym(n, want.sparsity_in(k)) for k, n in enumerate(want.name_in())]
        jacobians = [ca.Function("j", symbols, [ca.jacobian(ca.vcat(f.call(symbols)),
                                                            ca.vcat(symbols))])
                     for f in (got, want)]
        a, b = (j.call(inputs)[0].full() for j in jacobians)
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)  # same bound
