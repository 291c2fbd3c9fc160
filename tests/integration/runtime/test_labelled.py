"""Labelled results (runtime.labelled): a sensitivity's DataFrame against the closed-form
derivatives of a spring-mass oscillator, found by label whatever the order of parameters and
outputs asked; a linear model's A, B, C, D frames and modes frame against its closed forms."""

from __future__ import annotations

import numpy as np

import casmech
from casmech.optimal.sensitivity import sensitivity
from tests.helpers.statics_models import SPRING_MASS
from tests.integration.backends.test_parametric import MODEL

TIMES = [0.3, 0.7]


def test_sensitivity_frame_holds_the_closed_form_derivatives_by_label():
    """The block (m = 2, k = 100) starts 0.01 m from rest: x - 1 = 0.01 cos(w t), w =
    sqrt(k / m), so dx/dk = -0.01 t sin(w t) w / (2 k) and dx/dm = +0.01 t sin(w t) w / (2 m)."""
    model = casmech.loads(MODEL)
    frames = [sensitivity(model, names, outputs, TIMES).to_dataframe()
              for names, outputs in ((["m", "k"], ["block.x", "bob.x"]),
                                     (["k", "m"], ["bob.x", "block.x"]))]
    m, k, t = 2.0, 100.0, np.array(TIMES)
    w = np.sqrt(k / m)
    for frame in frames:
        assert frame.index.names == ["t", "output"]
        assert frame.attrs["units"] == {"block.x": "m", "bob.x": "m"}
        block = frame.xs("block.x", level="output")
        np.testing.assert_allclose(block.index, TIMES, rtol=0, atol=0)  # exact times
        # IDAS at rtol 1e-10 against the closed form: atol 1e-9 on values of 1e-2
        np.testing.assert_allclose(block["value"], 1 + 0.01 * np.cos(w * t), rtol=0, atol=1e-9)
        np.testing.assert_allclose(block["d/dk"], -0.01 * t * np.sin(w * t) * w / (2 * k),
                                   rtol=0, atol=1e-9)
        np.testing.assert_allclose(block["d/dm"], 0.01 * t * np.sin(w * t) * w / (2 * m),
                                   rtol=0, atol=1e-9)
        # the block does not depend on the pendulum, nor the pendulum on the spring
        np.testing.assert_allclose(frame.xs("bob.x", level="output")["d/dk"], 0.0, rtol=0,
                                   atol=1e-12)
    # the same numbers wherever they were in the arrays: to round-off
    np.testing.assert_allclose(frames[0].sort_index()[["d/dm", "d/dk"]],
                               frames[1].sort_index()[["d/dm", "d/dk"]], rtol=0, atol=1e-12)


def test_linear_model_frames_are_labelled_by_state_input_and_output():
    """SPRING_MASS (m = 3, k = 120) with the spring's tension and the push as inputs."""
    text = SPRING_MASS.replace("analysis: {type: statics}",
                               "analysis: {type: modal, inputs: [spring, push]}")
    linear = casmech.analyze(casmech.compile(casmech.loads(text))).linear_model
    frames = linear.to_dataframes()
    assert list(frames["B"].columns) == ["spring.force", "push.fx", "push.fy", "push.fz"]
    assert list(frames["A"].index) == linear.state_names == list(frames["A"].columns)
    assert list(frames["C"].index) == linear.output_names
    # the block's acceleration per unit input, by label: C_z B_w (C = [C_z, 0]); a tension
    # pulls it back (-1/m), the push along x forward (+1/m). Closed form: rtol 1e-12
    n = linear.basis.shape[1]
    acceleration = frames["C"].loc["block.dx"].iloc[:n].to_numpy() @ frames["B"].iloc[n:]
    np.testing.assert_allclose(acceleration[["spring.force", "push.fx"]], [-1 / 3, 1 / 3],
                               rtol=1e-12, atol=1e-15)
    modes = linear.modes_dataframe()
    assert modes.index.name == "mode" and list(modes.index) == [1]
    assert modes.attrs["units"]["frequency_hz"] == "Hz"
    # the damped oscillator (c = 4): undamped frequency sqrt(k/m)/2pi, ratio c / (2 sqrt(k m));
    # an eigenvalue of a 2x2 system: rtol 1e-10
    np.testing.assert_allclose(modes["frequency_hz"], np.sqrt(120 / 3) / (2 * np.pi),
                               rtol=1e-10, atol=0)
    np.testing.assert_allclose(modes["damping_ratio"], 4 / (2 * np.sqrt(120 * 3)), rtol=1e-10,
                               atol=0)
    shapes = linear.mode_shapes_dataframe()
    # the mode is the block along x alone, scaled to 1
    np.testing.assert_allclose(np.abs(shapes.loc[1, "block.dx"]), 1.0, rtol=1e-12, atol=0)
    np.testing.assert_allclose(np.abs(shapes.loc[1].drop("block.dx")), 0.0, rtol=0,
                               atol=1e-12)
