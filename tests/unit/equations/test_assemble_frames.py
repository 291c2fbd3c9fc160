"""equations.assemble builds each body's A(p) once (Coordinates.frame): the functions built that
way compute what the functions built with a fresh A(p) for every primitive and force compute."""

import numpy as np
import pytest

import casmech
from casmech.core import euler
from casmech.elements.primitives import Frame
from casmech.equations.assemble import Coordinates
from casmech.equations.functions import build_functions
from casmech.model.lower import lower
from tests.conftest import MODELS


def fresh_frame(self, k):
    return Frame(self.r(k), euler.rotation(self.p(k)))


@pytest.mark.parametrize("model", ["quadruped_legs", "bricard", "bushing_mount", "motor_crank",
                                   "user_force_pendulum", "flyball_governor"])
def test_shared_frames_compute_the_same_functions(model, monkeypatch):
    ir = lower(casmech.load(MODELS / f"{model}.yaml"))
    shared = build_functions(ir)
    monkeypatch.setattr(Coordinates, "frame", fresh_frame)
    fresh = build_functions(ir)
    assert shared.functions.keys() == fresh.functions.keys()
    rng = np.random.default_rng(0)
    for name, function in fresh.functions.items():
        inputs = [rng.uniform(-1, 1, function.sparsity_in(k).shape)
                  for k in range(function.n_in())]
        for a, b in zip(shared[name].call(inputs), function.call(inputs), strict=True):
            # the same operations on the same numbers: equal bit for bit
            np.testing.assert_array_equal(np.array(a), np.array(b), err_msg=name)
        assert shared[name].n_instructions() <= function.n_instructions()
