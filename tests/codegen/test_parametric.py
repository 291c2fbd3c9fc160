"""Parametric compiled libraries (codegen.parametric): `casmech run --set` with new values of a
mass and of a geometry parameter builds nothing after the first run, and each run gives the
physics of its values (closed-form periods); the library equals the interpreted bundle."""

import numpy as np
import pytest

import casmech
from casmech import codegen
from casmech.cli import main
from casmech.codegen import cache

# a spring-mass on a slide (period 2 pi sqrt(m / k)) and, independent of it, a pendulum of
# length L (small amplitude: 2 pi sqrt((I + M L^2) / (M g L)) with I = 1e-3 M)
MODEL = """casmech: 1
name: two_oscillators
parameters: {k: 100.0, m: 2.0, L: 1.0, M: 1.5, theta0: 0.01}
gravity: [0, -9.81, 0]
bodies:
  - {name: block, mass: m, inertia: [0.1, 0.1, 0.1], position: [1.01, 0, 0]}
  - {name: bob, mass: M, inertia: [1.0e-3 * M, 1.0e-3 * M, 1.0e-3 * M],
     position: [5 + L * sin(theta0), -L * cos(theta0), 0]}
joints:
  - {name: slide, type: translational, body_i: ground, body_j: block, at: [1, 0, 0],
     axis: [1, 0, 0]}
  - {name: pivot, type: revolute, body_i: ground, body_j: bob, at: [5, 0, 0], axis: [0, 0, 1]}
forces:
  - {name: spring, type: tsda, body_i: ground, at_i: [0, 0, 0], body_j: block,
     at_j: [1.01, 0, 0], stiffness: k, free_length: 1}
analysis: {type: dynamics, t_end: 4, output_step: 0.002, rtol: 1.0e-10, atol: 1.0e-12}
"""
G = 9.81


def period(t: np.ndarray, x: np.ndarray) -> float:
    """Twice the mean time between zero crossings of x (linear interpolation between rows)."""
    k = np.flatnonzero(np.sign(x[:-1]) != np.sign(x[1:]))
    crossings = t[k] - x[k] * (t[k + 1] - t[k]) / (x[k + 1] - x[k])
    assert len(crossings) >= 3
    return 2 * float(np.mean(np.diff(crossings)))


def expected(values: dict) -> tuple[float, float]:
    v = {"k": 100.0, "m": 2.0, "L": 1.0} | values
    return (2 * np.pi * np.sqrt(v["m"] / v["k"]),
            2 * np.pi * np.sqrt((1e-3 + v["L"] ** 2) / (G * v["L"])))


def run(path, out, mode: str, values: dict, formulation: str) -> np.ndarray:
    sets = [item for name, value in values.items() for item in ("--set", f"{name}={value}")]
    assert main(["run", str(path), "--out", str(out), "--mode", mode, "--formulation",
                 formulation, *sets]) == 0
    return np.genfromtxt(out / "results.csv", delimiter=",", names=True)


@pytest.fixture
def builds(monkeypatch) -> list:
    calls = []
    original = codegen.build_libraries
    monkeypatch.setattr(codegen, "build_libraries",
                        lambda *args, **kwargs: calls.append(args) or original(*args, **kwargs))
    return calls


@pytest.mark.parametrize("mode", ["compiled", "interpreted"])
def test_set_sequence_builds_once_and_follows_the_values(tmp_path, toolchain, cache_root, builds,
                                                         mode):
    path = tmp_path / "oscillators.yaml"
    path.write_text(MODEL)
    before = set(cache.entries(cache_root))
    # the joint formulation (a tree: ODE in joint coordinates), then the library's r-p DAE
    runs = [({"m": 2}, "joint"), ({"m": 3}, "joint"), ({"L": 2.0}, "joint"), ({"m": 3}, "rp"),
            ({"L": 2.0}, "rp")]
    for number, (values, formulation) in enumerate(runs):
        rows = run(path, tmp_path / f"out{number}", mode, values, formulation)
        spring, pendulum = expected(values)
        # 1e-4: the crossings are interpolated between rows 2 ms apart (error ~1e-6 s), the
        # pendulum's 0.01 rad amplitude adds theta0^2/16 = 6e-6 to its period
        np.testing.assert_allclose(period(rows["t"], rows["blockx"] - 1.0), spring,
                                   rtol=1e-4, atol=0)
        np.testing.assert_allclose(period(rows["t"], rows["bobx"] - 5.0), pendulum,
                                   rtol=1e-4, atol=0)
        assert len(builds) == (1 if mode == "compiled" else 0)  # the first run only
    new = set(cache.entries(cache_root)) - before
    assert len(new) == (1 if mode == "compiled" else 0)  # one library for every value


def test_library_equals_interpreted_at_other_values(tmp_path, toolchain, cache_root):
    """Every function of the bound library (the DAE residuals with d after p) equals the
    interpreted bundle of the model loaded with those values."""
    path = tmp_path / "oscillators.yaml"
    path.write_text(MODEL)
    rng = np.random.default_rng(3)
    for values in ({}, {"k": "130", "L": "1.7", "theta0": "0.2"}):
        model = casmech.load(path, values)
        bound = codegen.compiled(model, toolchain, root=cache_root)
        assert codegen.mode_of(bound) == "compiled" and bound.data is not None
        plain = casmech.compile(model)
        for name, function in plain.functions.items():
            args = [rng.standard_normal(function.sparsity_in(k).shape)
                    for k in range(function.n_in())]
            for got, want in zip(bound.evaluate(name, *args), plain.evaluate(name, *args),
                                 strict=True):
                # the same SX expressions, in C against casadi's virtual machine: round-off
                np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
        for name in ("dae_rp", "dae_ggl_romega"):
            compiled_dae = bound[name]
            interpreted_dae = casmech.compiler.dae.residual(plain.functions, *(
                ("rp", "projection") if name == "dae_rp" else ("romega", "ggl")))
            args = [rng.standard_normal(interpreted_dae.sparsity_in(k).shape)
                    for k in range(4)]
            got = compiled_dae(*args[:3], np.concatenate([args[3].ravel(), bound.data]), [])
            want = interpreted_dae(*args)
            for g, w in zip(got[:2], want, strict=True):
                np.testing.assert_allclose(np.array(g), np.array(w), rtol=1e-12, atol=1e-12)
