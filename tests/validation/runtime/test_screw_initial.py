"""A screw's `initial:` (its angle and angle_dot; the displacement follows by the lead): the
nut posed along the thread and falling from an initial spin, against the closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest

import casmech
from casmech.api import results_table
from casmech.errors import ModelError

G, M_NUT, J_NUT, LEAD = 9.81, 0.5, 1e-4, 0.01
SCREW = f"""casmech: 1
name: lead_screw
gravity: [0, 0, -{G}]
bodies:
  - {{{{name: nut, mass: {M_NUT}, inertia: [0.0002, 0.0002, {J_NUT}], position: [0, 0, 0.3]}}}}
joints:
  - {{{{name: thread, type: screw, body_i: ground, body_j: nut, at: [0, 0, 0.3], axis: [0, 0, 1],
     lead: {LEAD}, initial: {{initial}}}}}}
analysis: {{{{type: dynamics, t_end: 1, output_step: 0.05, rtol: 1e-11, atol: 1e-12,
           formulation: {{formulation}}}}}}
"""


@pytest.mark.parametrize("formulation", ["rp", "romega"])
def test_a_nut_falls_from_an_initial_spin_along_the_closed_form(formulation):
    """angle0 = 20 rad (three turns), angle_dot0 = 30 rad/s: s = L / (2 pi) (angle0 +
    angle_dot0 t) - a t^2 / 2, a = g m / (m + J (2 pi / L)^2)."""
    angle, rate = 20.0, 30.0
    text = SCREW.format(initial=f"{{angle: {angle}, angle_dot: {rate}}}",
                        formulation=formulation)
    functions = casmech.compile(casmech.loads(text))
    result = casmech.analyze(functions)
    names, values = results_table(functions, result)
    columns = dict(zip(names, values.T, strict=True))
    t = np.array(result.times)
    a = G * M_NUT / (M_NUT + J_NUT * (2 * math.pi / LEAD) ** 2)
    s = LEAD / (2 * math.pi) * (angle + rate * t) - a * t ** 2 / 2
    # the closed form integrated at rtol 1e-11 (some 1e-11 m)
    np.testing.assert_allclose(columns["thread.displacement"], s, rtol=1e-9, atol=1e-10)
    # posed exactly on the thread: the nut starts where the lead puts it, at the given spin
    np.testing.assert_allclose(columns["nut.z"][0], 0.3 + LEAD * angle / (2 * math.pi),
                               rtol=1e-12, atol=0)  # one rigid motion: roundoff
    np.testing.assert_allclose(columns["nut.wz"][0], rate, rtol=1e-12, atol=0)  # the same
    # the angle column is in (-pi, pi]: 20 rad less three turns
    np.testing.assert_allclose(columns["thread.angle"][0], angle - 6 * math.pi, rtol=0,
                               atol=1e-12)  # the posing's roundoff


def test_a_screw_takes_no_initial_displacement():
    text = SCREW.format(initial="{displacement: 0.01}", formulation="auto")
    with pytest.raises(ModelError) as raised:
        casmech.loads(text)
    assert [d.code for d in raised.value.diagnostics] == ["E101"]
    assert raised.value.diagnostics[0].path == "joints[0].initial.displacement"
