"""Compiled code (casmech.backends) runs motors and tables like the interpreted functions: the
effort motors live in ModelIR.motors beside ModelIR.forces, and a table is an if_else tree of
plain SX, so generated C must give the same numbers, reactions of motors that read the joint
rate included (one gcc build of the kernel C into a private cache: 5 s here)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

import casmech
from tests.unit.equations.test_mapped import MOTORS

# the motors model of the mapped-bundle tests, its pivot driven by a periodic table instead
MODEL = MOTORS.replace("name: motors\n", "name: motors_codegen\n").replace(
    "driver: {angle: 0.3 * sin(t)}",
    "driver: {angle: {table: theta.csv, column: theta, periodic: true}}")


@pytest.mark.slow  # long validation: `python -m pytest -m slow` runs it
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
