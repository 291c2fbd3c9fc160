"""The DAE residual's two evaluations: as a sum of elements (formulations.residuals: one kernel per
joint, body and force element, mapped) it equals formulations.dae's residual over the inline
bundle (the whole model's matrices, differentiated as one graph): the residual, and
IDAS's Jacobian blocks d(ode, alg)/d(x, z) (jacF) against CasADi's SX Jacobian, in value and
sparsity, and the Jacobian patterns of every block (t and p too) the library declares, for
both formulations and stabilizations, with rows masked at random (w in {0, 1}) and random row
scales (s, s_phi). The element functions are MX graphs evaluated here directly (no C compiler
needed)."""

import itertools

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.equations import evaluation, force_kernels, rows
from casmech.formulations import dae, residual_groups, residuals
from casmech.formulations.table import BODY_FORMS
from casmech.model.lower import lower
from tests.unit.equations.test_mapped import EVERY_MODEL, MODELS, ROOT

CASES = list(itertools.product(BODY_FORMS, residuals.KINDS))


def _inputs(reference: ca.Function, m: int, rng) -> list[ca.DM]:
    """Random (t, x, z) and p = [t0, w, s (, s_phi)]: rows kept or masked at random, scales
    in [0.5, 2]."""
    values = [ca.DM(reference.sparsity_in(k), rng.uniform(-1, 1, reference.nnz_in(k)))
              for k in range(4)]
    n_p = reference.nnz_in(3)
    values[3][1:] = rng.uniform(0.5, 2.0, n_p - 1)
    values[3][1:1 + m] = rng.integers(0, 2, m)
    return values


def _blocks(reference: ca.Function) -> ca.Function:
    """jacF of the SX residual, as casadi's IDAS interface builds it for an SX DAE."""
    symbols = [ca.SX.sym(n, reference.sparsity_in(k)) for k, n in enumerate(reference.name_in())]
    ode, alg = reference(*symbols)
    x, z = symbols[1], symbols[2]
    return ca.Function("jacF", symbols, [ca.jacobian(ode, x), ca.jacobian(alg, x),
                                         ca.jacobian(ode, z), ca.jacobian(alg, z)])


def _close(got, want, message: str) -> None:
    want = np.array(ca.DM(want).full())
    # the same equations in another order of sums: round-off, relative to the output's scale
    # (measured <= 2e-15 of it)
    np.testing.assert_allclose(np.array(ca.DM(got).full()), want, rtol=1e-12,
                               atol=1e-12 * max(1.0, np.max(np.abs(want), initial=0)),
                               err_msg=message)


def check(ir, unrolled: dict, form: str, kind: str, seed: int = 5, same_pattern=True) -> None:
    reference = dae.residual(unrolled, form, kind)
    oracle = residuals.oracle(ir, form, kind)
    function = oracle[residuals.name(form, kind)]
    assert function.name_in() == ca.dyn_in() and function.name_out() == ca.dyn_out()
    assert [function.size_in(k) for k in range(4)] == [reference.size_in(k) for k in range(4)]
    blocks = _blocks(reference)
    rng = np.random.default_rng(seed)
    m = residual_groups.Indices(ir, form, kind).m
    assert function.size_in(3) == reference.size_in(3) == (dae.parameters(unrolled, form, kind), 1)
    for _ in range(2):
        inputs = _inputs(reference, m, rng)
        u = ca.DM(0, 1)
        for a, b in zip(function.call([*inputs, u])[:2], reference.call(inputs), strict=True):
            _close(a, b, f"{reference.name()} residual")
        for a, b in zip(oracle["daeF"].call([*inputs, u]), reference.call(inputs), strict=True):
            _close(a, b, f"{reference.name()} daeF")
        for k, (a, b) in enumerate(zip(oracle["jacF"].call([*inputs, u]), blocks.call(inputs),
                                       strict=True)):
            _close(ca.densify(a), ca.densify(b), f"{reference.name()} {blocks.name_out(k)}")
    for name_, patterns in residuals.jacobian_patterns(oracle).items():
        # every block holds the SX residual's pattern (t and p included): what casadi reads
        want = [reference.jac_sparsity(o, i) for o in range(2) for i in range(4)]
        got = [patterns[o * 5 + i] for o in range(2) for i in range(4)]
        assert all(_triplets(w) <= _triplets(g) for w, g in zip(want, got, strict=True)), name_
    for k in range(4):
        mine, theirs = oracle["jacF"].sparsity_out(k), blocks.sparsity_out(k)
        if same_pattern:
            assert mine == theirs, (reference.name(), k)
        else:  # vectors as data: constants that cancel in the unrolled SX stay entries here
            assert mine.shape == theirs.shape and _triplets(theirs) <= _triplets(mine)


def _triplets(sparsity: ca.Sparsity) -> set:
    return set(zip(*sparsity.get_triplet(), strict=True))


@pytest.mark.parametrize("name", list(MODELS))
def test_element_residuals_equal_compiler_dae(name):
    model = MODELS[name]()
    ir, unrolled = lower(model), casmech.compile(model, "interpreted").functions
    for form, kind in CASES:
        check(ir, unrolled, form, kind)


@pytest.mark.parametrize("file", EVERY_MODEL)
def test_every_model_element_residuals_equal_compiler_dae(file):
    """Every model of models/; one whose rows' vectors are kernel data (past BAKE_LIMIT
    geometries) may keep structural entries that are 0 in value (test_vectors_as_data)."""
    model = casmech.load(ROOT / "models" / file)
    ir, unrolled = lower(model), casmech.compile(model, "interpreted").functions
    baked = all(key.values is not None for key in rows.row_keys(ir))
    for form, kind in CASES:
        check(ir, unrolled, form, kind, same_pattern=baked)


def test_vectors_as_data(monkeypatch):
    """Past BAKE_LIMIT geometries the joints' vectors are kernel data: the same values."""
    monkeypatch.setattr(rows, "BAKE_LIMIT", 0)
    model = MODELS["slider_crank"]()
    ir = lower(model)
    assert all(key.values is None for key in rows.row_keys(ir))
    for form, kind in CASES:
        check(ir, casmech.compile(model, "interpreted").functions, form, kind,
              same_pattern=False)


def test_force_elements_without_a_kernel(monkeypatch):
    """Force elements without a kernel get one each, over the coordinates they read."""
    monkeypatch.setattr(force_kernels, "kernelised", lambda force: False)
    model = MODELS["motors"]()
    for form, kind in CASES:
        check(lower(model), casmech.compile(model).functions, form, kind)


def test_elements_per_joint_and_body():
    """One element per joint (its rows together), body and force: a chain of 4 has 2 joint
    kernels (the ground joint's rows bake ground, the others share one), 1 body kernel."""
    ir = lower(MODELS["chain4"]())
    ix = residual_groups.Indices(ir, "rp", "ggl")
    t, p = ca.MX.sym("t"), ca.MX.sym("p", ix.n_p)
    groups = residuals.element_sum(ir, ix, t, ix.constants(p),
                                   evaluation.Evaluation.of(False)).groups
    assert [g.count for g in groups] == [1, 3, 4]


def test_small_models_compile_the_unrolled_dae():
    """oracles: a model the switch evaluates inline (WHERE_INLINE["dae_library"]) whose inline
    residual and Jacobian stay within UNROLLED_INSTRUCTIONS gets formulations.dae's SX residual
    itself (an SXFunction, with AD's jacF); a larger one the element sum (an MX graph over the
    kernels)."""
    from tests.unit.equations.test_mapped import chain_text

    limit = evaluation.WHERE_INLINE["dae_library"]
    for bodies, unrolled in ((2, True), (limit + 1, False)):
        ir = lower(casmech.loads(chain_text(bodies)))
        for name, functions in residuals.oracles(ir).items():
            assert functions["daeF"].is_a("SXFunction") == unrolled, (bodies, name)
            size = sum(functions[f].n_instructions() for f in ("daeF", "jacF"))
            assert not unrolled or size <= residuals.UNROLLED_INSTRUCTIONS
