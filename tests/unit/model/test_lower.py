"""model/lower.py: a run lowers its model once (the model lowered last gives its IR again), and
the bodies' rotation matrices computed by one mapped call are traced.numeric's per body."""

import numpy as np

from casmech.core import euler, traced
from casmech.model import lower as lowering
from casmech.schema import load_model
from tests.conftest import ROOT


def test_the_model_lowered_last_gives_its_ir_again():
    path = ROOT / "models" / "double_pendulum.yaml"
    model = load_model(path)
    ir = lowering.lower(model)
    assert lowering.lower(model) is ir
    again = load_model(path)  # an equal model, another object: lowered anew
    other = lowering.lower(again)
    assert other is not ir
    for a, b in zip(ir.bodies, other.bodies, strict=True):
        np.testing.assert_array_equal(b.r0, a.r0)
        np.testing.assert_array_equal(b.p0, a.p0)


def test_the_mapped_rotations_are_the_per_body_ones():
    model = load_model(ROOT / "models" / "quadruped_legs.yaml")  # 4 of 9 bodies turned
    mapped = lowering._rotations(model.bodies)
    for body, rotation in zip(model.bodies, mapped, strict=True):
        # the same SX arithmetic evaluated once per body or mapped: the same bits
        np.testing.assert_array_equal(rotation,
                                      traced.numeric(euler.rotation, body.euler_parameters))
        assert rotation.flags.c_contiguous
