"""The compiled bundle is the interpreted one: same functions, names, sparsity, values on random
inputs, and the same Jacobians through the generated jac_<name> or fwd1_/adj1_<name> (what an
MX graph over the library, such as the augmented-Lagrangian ODE, differentiates)."""

import casadi as ca
import numpy as np
import pytest

from casmech.backends import codegen, generate, manifest
from casmech.equations.functions import mapped_functions
from casmech.formulations import dae
from casmech.model.lower import lower
from tests.unit.equations.test_mapped import SUBSET

# the residuals a compiled bundle carries besides the interpreted functions (formulations.dae)
RESIDUALS = ["dae_ggl_rp", "dae_rp", "dae_ggl_romega", "dae_romega"]


@pytest.fixture(scope="module", params=["parametric", "mapped"])
def compiled(request, model, toolchain, cache_root):
    """Both libraries of the session's model: the parametric one (codegen.parametric: it has
    parameters), the mapped one (equations.functions.mapped_functions, the values built in)."""
    return codegen.compiled(model, toolchain, root=cache_root,
                            parametric_library=request.param == "parametric")


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
    # the compiled bundle carries the DAE residuals as well (formulations.dae uses them)
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
    """Names, sizes, sparsity and library in manifest.json rebuild the functions' own patterns
    (those code generation compiled: equations.functions.mapped_functions, and the DAE residuals of
    formulations.residuals, each in a library of its own)."""
    info = manifest.read(build_dir)
    entries = {e["name"]: e for e in info["functions"]}
    ir = lower(model)
    built = {**mapped_functions(ir),
             **{name: oracle[name] for name, oracle in codegen.dae_oracles(ir).items()}}
    assert set(entries) == set(built) == {*interpreted.functions, *RESIDUALS}
    for name, function in built.items():
        entry = entries[name]
        assert [i["name"] for i in entry["inputs"]] == function.name_in()
        assert [o["name"] for o in entry["outputs"]] == function.name_out()
        for k, output in enumerate(entry["outputs"]):
            assert manifest.sparsity(output) == function.sparsity_out(k)
        assert entry["jacobian"] == (name in generate.DIFFERENTIATED)
        assert entry["forward_reverse"] == (name in generate.DIRECTIONAL)
        library = generate.dae_library(name) if name in RESIDUALS else info["library"]
        assert entry["library"] == library and (build_dir / library).is_file()


def _sx_blocks(residual: ca.Function) -> ca.Function:
    """jacF as casadi's IDAS interface builds it for an SX DAE."""
    symbols = [ca.SX.sym(n, residual.sparsity_in(k)) for k, n in enumerate(residual.name_in())]
    ode, alg = residual(*symbols)
    x, z = symbols[1], symbols[2]
    return ca.Function("jacF", symbols, [ca.jacobian(ode, x), ca.jacobian(alg, x),
                                         ca.jacobian(ode, z), ca.jacobian(alg, z)])


@pytest.mark.parametrize("seed", [0, 1])
def test_dae_residuals_and_jacobians_equal_interpreted(compiled, interpreted, build_dir, seed):
    """The compiled DAEs (both stabilizations, both formulations) are what IDAS integrates:
    with the integrator's signature, and IDAS takes daeF and jacF from their libraries; their
    values equal formulations.dae over the interpreted bundle and its SX Jacobian."""
    rng = np.random.default_rng(seed)
    for name in RESIDUALS:
        form, kind = name.split("_")[-1], "ggl" if "ggl" in name else "projection"
        want = dae.residual(interpreted.functions, form, kind)
        got = compiled[name]
        assert got.name_in() == ca.dyn_in() and got.name_out() == ca.dyn_out()
        integrator = ca.integrator("i", "idas", dae.problem(got), 0.0, [0.1])
        dae_f, jac_f = integrator.get_function("daeF"), integrator.get_function("jacF")
        assert dae_f.class_name() == jac_f.class_name() == "External"
        for function in (got, dae_f):  # Jacobian patterns from the library, not dense
            assert function.jac_sparsity(1, 1) == jac_f.sparsity_out(1), name
        inputs = _random_inputs(want, rng)
        m = dae.sizes(interpreted.functions, form)[2]
        inputs[3][1:] = rng.uniform(0.5, 2.0, want.nnz_in(3) - 1)  # row scales s (, s_phi)
        inputs[3][1:1 + m] = rng.integers(0, 2, m)  # w: rows kept or masked
        # a parametric library's residuals take the model data after p (codegen.parametric)
        given = [*inputs[:3], ca.vertcat(inputs[3], ca.DM(
            compiled.data if compiled.data is not None else ca.DM(0, 1))), ca.DM(0, 1)]
        # same equations, sums in another order: the compiled-vs-interpreted bound
        for a, b in zip(got.call(given)[:2], want.call(inputs), strict=True):
            np.testing.assert_allclose(a.full(), b.full(), rtol=1e-12, atol=1e-12, err_msg=name)
        for a, b in zip(dae_f.call(given), want.call(inputs), strict=True):
            np.testing.assert_allclose(a.full(), b.full(), rtol=1e-12, atol=1e-12, err_msg=name)
        blocks = _sx_blocks(want).call(inputs)
        for a, b in zip(jac_f.call(given), blocks, strict=True):
            np.testing.assert_allclose(ca.densify(a).full(), ca.densify(b).full(), rtol=1e-12,
                                       atol=1e-12, err_msg=name)  # the same bound
