"""Parametric compiled libraries (codegen.parametric): `casmech run --set` with new values of a
mass and of a geometry parameter builds nothing after the first run, and each run gives the
physics of its values (closed-form periods); the library equals the interpreted bundle."""

import json

import numpy as np
import pytest

import casmech
from casmech.backends import cache, codegen, parametric
from casmech.backends.load import externals
from casmech.cli import main
from casmech.runtime.joint_dynamics import joint_system
from tests.helpers.codegen import counted_builds, model_libraries

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
    return counted_builds(monkeypatch, codegen)


@pytest.mark.parametrize("mode", ["compiled", "interpreted"])
def test_set_sequence_builds_once_and_follows_the_values(tmp_path, toolchain, builds, mode,
                                                         monkeypatch):
    # a cache of its own: the session's may hold this library already (test_set.py builds it)
    cache_root = tmp_path / "cache"
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(cache_root))
    path = tmp_path / "oscillators.yaml"
    path.write_text(MODEL)
    before = model_libraries(cache_root)
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
    new = model_libraries(cache_root) - before
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
        plain = casmech.compile(model, "interpreted")
        for name, function in plain.functions.items():
            args = [rng.standard_normal(function.sparsity_in(k).shape)
                    for k in range(function.n_in())]
            for got, want in zip(bound.evaluate(name, *args), plain.evaluate(name, *args),
                                 strict=True):
                # the same SX expressions, in C against casadi's virtual machine: round-off
                np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
        for name in ("dae_rp", "dae_ggl_romega"):
            compiled_dae = bound[name]
            interpreted_dae = casmech.formulations.dae.residual(plain.functions, *(
                ("rp", "projection") if name == "dae_rp" else ("romega", "ggl")))
            args = [rng.standard_normal(interpreted_dae.sparsity_in(k).shape)
                    for k in range(4)]
            got = compiled_dae(*args[:3], np.concatenate([args[3].ravel(), bound.data]), [])
            want = interpreted_dae(*args)
            for g, w in zip(got[:2], want, strict=True):
                np.testing.assert_allclose(np.array(g), np.array(w), rtol=1e-12, atol=1e-12)


def case_text(case: str) -> str:
    """A model of formulations' PARAMETRIC_CASES over 1 s: the text of every test here that
    runs it, so that they share its parametric library (the text is part of its key)."""
    from tests.unit.formulations.test_joint_system import PARAMETRIC_CASES

    return PARAMETRIC_CASES[case][0].replace("t_end: 2", "t_end: 1")


@pytest.mark.parametrize("case, sets", [
    ("double_pendulum", [{"m1": 2.0, "L2": 1.3}, {"m2": 0.4, "L1": 0.7}]),  # a tree
    ("four_bar", [{"b": 2.2}, {"b": 1.9, "m": 1.5}]),  # a loop: its projected ODE
    ("gear_pair", [{"m": 0.7}, {"l": 0.25}]),  # a coupling: its row among the loop rows
])
def test_set_runs_joint_coordinates_compiled_and_builds_once(tmp_path, toolchain, cache_root,
                                                             builds, monkeypatch, case, sets):
    """`casmech run --set` twice on a compiled model: the first run builds the parametric
    library (with the joint functions), the second builds nothing; both run in joint
    coordinates from that library and move as the r-p DAE at the same values does."""

    path = tmp_path / f"{case}.yaml"
    path.write_text(case_text(case))
    entries = []  # the cache's entries after each value's runs
    for number, values in enumerate(sets):
        out = tmp_path / f"joint{number}"
        joint = run(path, out, "compiled", values, "auto")
        metadata = json.loads((out / "metadata.json").read_text())
        assert metadata["mode"] == "compiled"
        assert metadata["result"]["formulation"] == "joint"
        assert metadata["result"]["integrator"] == "dop853"  # method auto, no force elements
        assert len(builds) == 1  # the first run only
        rp = run(path, tmp_path / f"rp{number}", "compiled", values, "rp")
        for name in joint.dtype.names:
            scale = max(1.0, float(np.max(np.abs(rp[name]))))
            # two formulations at rtol 1e-8 over 1 s, relative to each column's largest
            # value: the chaotic double pendulum's accelerations differ by 1.3e-5 at most
            np.testing.assert_allclose(joint[name], rp[name], rtol=0, atol=1e-4 * scale,
                                       err_msg=f"{name} at {values}")
        entries.append(set(cache.entries(cache_root)))
    # one library for every value (and, for the loop, one of its singular-pose check)
    assert entries[1] == entries[0]
    # in process: the joint system is the library's, bound to these values (nothing built),
    # its externals loaded once for every value (a sweep's samples)
    loads = []
    monkeypatch.setattr(parametric, "externals", lambda *a: loads.append(a) or externals(*a))
    parametric._externals.cache_clear()
    for values in sets:
        given = {name: str(value) for name, value in values.items()}
        functions = codegen.compiled(casmech.load(path, given), toolchain, root=cache_root)
        system = joint_system(functions)
        assert system.dynamics is functions.joint_functions[system.dynamics.name()]
    assert len(builds) == 1 and len(loads) == 1


def test_no_joint_functions_for_loops_through_a_floating_body():
    """ocp_arm3d's payload is held by six basic constraints: formulation auto runs rp there
    (runtime.auto_formulation), so its library compiles no joint functions; a tree's has them."""
    from casmech.model import parametric as model_data
    from casmech.model.lower import lower
    from tests.conftest import MODELS

    def names(path) -> set:
        return set(parametric.joint_functions(model_data.split(lower(casmech.load(path)))))

    assert names(MODELS / "ocp_arm3d.yaml") == set()
    assert {"joint_ode", "joint_motion", "joint_data"} <= names(MODELS / "double_pendulum.yaml")


def test_a_parametric_library_solves_its_loop_rows():
    """The four-bar's parametric library (its joint functions bound to the values): a run's
    loop multipliers are solved at each row's state by default (loop_rows solved), as an
    interpreted bundle's are: they are the r-p multipliers at the row's (q, q_dot) to
    roundoff, where IDAS's algebraic states (loop_rows integrator) carry their own error."""
    from tests.integration.runtime.test_loop_rows import rp_multipliers

    model = casmech.loads(case_text("four_bar"), overrides={"b": "2.2"})
    # the session's library of this structure when the four-bar's --set runs came first (the
    # same text: its digest keys the library)
    bundle = casmech.compile(model, "compiled")
    assert bundle.parametric is not None and bundle.joint_functions is not None
    plain = casmech.compile(model)

    def worst(options: dict) -> float:
        result = casmech.analyze(bundle, "dynamics", formulation="joint", method="bdf",
                                 t_end=0.5, rtol=1e-6, atol=1e-8, options=options)
        errors = []
        for k in range(0, len(result), 10):
            rp = rp_multipliers(plain, result.times[k], result.q[k], result.q_dot[k])
            errors.append(np.abs(result.lam[k][:len(rp)] - rp).max() / np.abs(rp).max())
        return max(errors)

    solved, integrator = worst({}), worst({"loop_rows": "integrator"})
    assert solved < 1e-8  # two solves of the same saddle system: roundoff times its condition
    assert integrator > 100 * solved  # IDAS's interpolated algebraic states at rtol 1e-6
