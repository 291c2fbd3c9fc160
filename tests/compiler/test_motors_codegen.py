"""Compiled code (casmech.codegen) runs motors and tables like the interpreted functions: the
effort motors live in ModelIR.motors beside ModelIR.forces, and a table is an if_else tree of
plain SX, so generated C must give the same numbers, reactions of motors that read the joint
rate included (one gcc build of the kernel C into a private cache: 5 s here)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

import casmech

MODEL = """
casmech: 1
name: motors_codegen
bodies:
  - {name: bar, mass: 5, inertia: [2, 2, 0.01], position: [0, 0, -1]}
  - {name: disc, mass: 1, inertia: [0.15, 0.15, 0.25], position: [0, 0, -3]}
  - {name: block, mass: 2, inertia: [0.1, 0.1, 0.1], position: [1, 0, -3]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [1, 0, 0],
     driver: {angle: {table: theta.csv, column: theta, periodic: true}}}
  - {name: spin, type: revolute, body_i: bar, body_j: disc, at: [0, 0, -3], axis: [0, 0, 1],
     motor: {torque: "2 - 0.1*angle - 0.3*angle_dot"}}
  - {name: slide, type: translational, body_i: disc, body_j: block, at: [1, 0, -3],
     axis: [1, 0, 0], motor: {force: "-3*displacement + sin(t) - 0.2*displacement_dot"}}
"""


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs a C compiler")
def test_compiled_motors_and_tables_equal_interpreted(tmp_path, monkeypatch):
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))
    t = np.linspace(0, np.pi, 41)
    rows = "\n".join(f"{a!r},{b!r}" for a, b in zip(t.tolist(), (np.cos(2 * t) / 2).tolist(),
                                                     strict=True))
    (tmp_path / "theta.csv").write_text("t,theta\n" + rows + "\n", encoding="utf-8")
    (tmp_path / "model.yaml").write_text(MODEL, encoding="utf-8")
    model = casmech.load(tmp_path / "model.yaml")
    interpreted, compiled = casmech.compile(model), casmech.compile(model, mode="compiled")
    rng = np.random.default_rng(0)
    for name in ("phi", "nu", "gamma", "generalized_forces", "reactions"):
        function = interpreted[name]
        args = [rng.normal(size=function.size_in(k)) for k in range(function.n_in())]
        expected = interpreted.evaluate(name, *args)
        got = compiled.evaluate(name, *args)
        for a, b in zip(expected, got, strict=True):
            assert np.isfinite(a).all(), name  # assert_allclose would take NaN == NaN
            # the same SX in C: rounding only (measured 0)
            np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)
