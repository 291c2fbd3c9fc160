"""Compiled and interpreted simulations of one model agree to the solver tolerance, and each
result says which mode ran. IDAS integrates the library's dae_<formulation> with its Jacobian
(formulations.dae takes it from the bundle); the Runge-Kutta fallback at singular poses evaluates
the library's functions in an MX graph.

"The solver tolerance" is measured, not assumed: the integration error of the rtol 1e-8 run is
its distance to a run at rtol 1e-11 (both interpreted). Compiled and interpreted may take
different steps (their Jacobians round differently, IDAS reuses them), so they agree to within
that error, not to 1e-12."""

import numpy as np
import pytest

import casmech
from tests.helpers.reference_data import VALIDATION_MODELS

STATES = ("x", "y", "z", "e0", "e1", "e2", "e3", "vx", "vy", "vz", "wx", "wy", "wz")


def _run(functions, rtol, atol, formulation):
    result = casmech.analyze(functions, "dynamics", t_end=0.3, output_step=0.05, rtol=rtol,
                             atol=atol, formulation=formulation)
    names, values = casmech.results_table(functions, result)
    return result.metadata["mode"], list(names), np.asarray(values)


@pytest.mark.parametrize("formulation", ["rp", "romega"])
def test_compiled_and_interpreted_dynamics_agree(compiled, interpreted, formulation):
    mode_c, names, got = _run(compiled, 1e-8, 1e-10, formulation)
    mode_i, _, want = _run(interpreted, 1e-8, 1e-10, formulation)
    _, _, reference = _run(interpreted, 1e-11, 1e-13, formulation)
    assert (mode_c, mode_i) == ("compiled", "interpreted")
    assert got.shape == want.shape == reference.shape and got.shape[0] == 7
    states = [k for k, name in enumerate(names) if name.split(".")[-1] in STATES]
    for columns in (states, slice(None)):  # states, then every column (a, alpha, reactions)
        error = np.max(np.abs(want - reference)[:, columns])  # measured 1.3e-7..1.8e-7 (states)
        # a sane loose run: below 1e-4 of the columns' scale (reactions reach ~10 N; with the
        # drift allowed at atol 1e-10, 1e-8, their error measured 1.1e-4 N)
        assert 0 < error < 1e-4 * max(1.0, np.max(np.abs(reference[:, columns])))
        # measured (states): compiled - interpreted 1.2e-12 (rp), 2.6e-12 (romega) with the
        # compiled dae_<form> built from mapped kernels (the same equations, sums in another
        # order), against each run's own error 2.3e-7..3.6e-7
        assert np.max(np.abs(got - want)[:, columns]) <= 2 * error
        assert np.max(np.abs(got - reference)[:, columns]) <= 3 * error


@pytest.mark.slow  # builds a C library: the compiled set
def test_compiled_fallback_at_a_singular_pose():
    """IFToMM A02 (N = 2) over its first flat pose (0.72 s), where both DAEs fail and the
    projected Runge-Kutta steps run on the compiled functions (no derivatives needed)."""
    model = casmech.load(VALIDATION_MODELS / "iftomm_a02_four_bar_N2.yaml")
    runs = {}
    for mode in ("compiled", "interpreted"):
        functions = casmech.compile(model, mode=mode)
        result = casmech.analyze(functions, "dynamics", t_end=1.0)
        assert result.metadata["mode"] == mode and result.metadata["augmented_from"] == 0.0
        runs[mode] = np.asarray(casmech.results_table(functions, result)[1])
    assert runs["compiled"].shape == runs["interpreted"].shape
    # the same steps (362) on the same equations: measured 1.2e-15 apart, roundoff of the C
    np.testing.assert_allclose(runs["compiled"], runs["interpreted"], rtol=0,
                               atol=1e-9 * max(1.0, np.max(np.abs(runs["interpreted"]))))
