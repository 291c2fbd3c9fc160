"""Statics and modal analyses on a compiled bundle (the tangent stiffness is differentiated from
the model rebuilt in SX) agree with the interpreted bundle."""

import numpy as np

import casmech


def test_modal_of_compiled_bundle_matches_interpreted(interpreted, compiled):
    expected = casmech.analyze(interpreted, "modal")
    got = casmech.analyze(compiled, "modal")
    assert got.metadata["mode"] == "compiled"
    # the model has a DOF of zero stiffness (a 0 Hz mode), along which the two runs may stop
    # at poses 1e-9 apart; the frequencies do not depend on it: the same equations in C,
    # roundoff-level agreement (rtol 1e-10)
    np.testing.assert_allclose(got.linear_model.frequency_hz,
                               expected.linear_model.frequency_hz, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(got.linear_model.damping_ratio,
                               expected.linear_model.damping_ratio, rtol=1e-8, atol=1e-12)
