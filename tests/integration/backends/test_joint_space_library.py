"""backends.joint_space_library: the joint space of a model compiled with mode "compiled" runs
in C, each function built when first used, and gives what the interpreted space of the same
model gives (formulations.joint_space's SX, evaluated by CasADi); one library per structure
serves every parameter value (`set` builds nothing) and follows the model's tables."""

import shutil

import numpy as np

import casmech
from tests.conftest import MODELS

FUNCTIONS = ("mass_matrix", "bias_forces", "forward_dynamics", "inverse_dynamics",
             "forward_dynamics_derivatives", "inverse_dynamics_derivatives",
             "forward_kinematics")


def _outputs(space, q, v, tau) -> list[np.ndarray]:
    """Every function's outputs at one state, as the NumPy calls give them."""
    return [space.mass_matrix(q), space.bias_forces(q, v), space.forward_dynamics(q, v, tau),
            space.inverse_dynamics(q, v, tau), *space.forward_dynamics_derivatives(q, v, tau),
            *space.inverse_dynamics_derivatives(q, v, tau), *space.forward_kinematics(q, v)]


def _state(space, rng):
    q = space.neutral + 0.3 * rng.standard_normal(space.nq)
    return q, rng.standard_normal(space.nv), rng.standard_normal(space.nv)


def test_the_compiled_space_gives_the_interpreted_ones_values(toolchain, builds):
    # a spherical joint (quaternion coordinates, nq > nv) and revolute ones
    model = casmech.load(MODELS / "heavy_top.yaml")
    compiled = casmech.joint_space(casmech.compile(model, "compiled"))
    interpreted = casmech.joint_space(model)
    assert type(compiled.calls).__name__ == "Calls" and compiled.nq == interpreted.nq
    built = len(builds)
    rng = np.random.default_rng(11)
    for _ in range(3):
        q, v, tau = _state(interpreted, rng)
        found, expected = _outputs(compiled, q, v, tau), _outputs(interpreted, q, v, tau)
        for a, b in zip(found, expected, strict=True):
            assert a.shape == b.shape
            # the same arithmetic, the constants read from the data input instead of folded
            # in: roundoff of O(1) quantities (masses, lengths, g of O(10))
            np.testing.assert_allclose(a, b, rtol=1e-11, atol=1e-11)
    # one library per function used, built on first use; the CasADi Functions call them
    assert len(builds) - built <= len(FUNCTIONS)
    a = compiled["forward_dynamics"](0.0, q, v, tau)
    np.testing.assert_allclose(np.ravel(a.full()), interpreted.forward_dynamics(q, v, tau),
                               rtol=1e-11, atol=1e-11)  # as above
    assert compiled["forward_dynamics"].name_in() == ["t", "q", "v", "tau"]


def test_set_builds_nothing_and_moves_the_physics(toolchain, builds, tmp_path):
    from tests.integration.backends.test_parametric import MODEL

    path = tmp_path / "oscillators.yaml"
    path.write_text(MODEL)
    model = casmech.compile(casmech.load(path), "compiled")
    rng = np.random.default_rng(4)
    first = casmech.joint_space(model)
    q, v, tau = _state(first, rng)
    before = _outputs(first, q, v, tau)  # every function built (or found) once
    built = len(builds)
    heavier = casmech.joint_space(model.set(m=3))
    found = _outputs(heavier, q, v, tau)
    assert len(builds) == built  # the same structure: the same libraries, no build
    # independent: the model loaded with m = 3, its space interpreted
    expected = _outputs(casmech.joint_space(casmech.load(path, {"m": "3"})), q, v, tau)
    for a, b in zip(found, expected, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-11, atol=1e-11)  # roundoff, as above
    assert not np.allclose(found[0], before[0])  # m moved the mass matrix


def test_a_changed_table_is_a_different_library(toolchain, tmp_path):
    # the follower's lift is a table of t (a prescribed coordinate): forward kinematics at
    # t = 0.4 s reads it; a table's data is not in the structure's signature
    for name in ("table_driver.yaml", "table_driver_profile.csv"):
        shutil.copy(MODELS / name, tmp_path / name)
    path, table = tmp_path / "table_driver.yaml", tmp_path / "table_driver_profile.csv"

    def lift() -> tuple[float, float]:
        model = casmech.load(path)
        compiled = casmech.joint_space(casmech.compile(model, "compiled"))
        interpreted = casmech.joint_space(model)
        heights = [space.forward_kinematics(space.neutral, t=0.4)[0][5]
                   for space in (compiled, interpreted)]
        return heights[0], heights[1]

    before = lift()
    rows = table.read_text().splitlines()
    header = next(k for k, row in enumerate(rows) if row.startswith("t,"))
    doubled = [f"{t},{2 * float(x)}" for t, x in (row.split(",") for row in rows[header + 1:])]
    table.write_text("\n".join(rows[:header + 1] + doubled) + "\n")
    after = lift()
    for compiled, interpreted in (before, after):
        np.testing.assert_allclose(compiled, interpreted, rtol=0, atol=1e-13)  # roundoff
    assert abs(after[0] - before[0]) > 1e-3  # the lift at 0.4 s doubled (~10 mm)


def test_a_tree_above_the_inline_bodies_keeps_the_interpreted_space(toolchain, builds,
                                                                    monkeypatch):
    from casmech.equations import evaluation

    compiled = casmech.compile(casmech.load(MODELS / "heavy_top.yaml"), "compiled")
    monkeypatch.setitem(evaluation.WHERE_INLINE, "parametric", compiled.n_bodies - 1)
    built = len(builds)
    space = casmech.joint_space(compiled)
    q = space.neutral
    space.forward_dynamics(q, np.zeros(space.nv), np.zeros(space.nv))
    assert len(builds) == built and space["forward_dynamics"].is_a("SXFunction")


def test_auto_compiles_what_the_cache_holds_and_builds_nothing(toolchain, tmp_path,
                                                                monkeypatch):
    from casmech.backends import cache
    from casmech.backends.joint_space_library import CompiledSpace
    from casmech.model.lower import lower

    root = tmp_path / "cache"  # of its own: the session's may hold these libraries
    monkeypatch.setenv("CASMECH_CACHE_DIR", str(root))
    monkeypatch.setenv("CASMECH_BACKGROUND_BUILD", "0")
    model = casmech.load(MODELS / "heavy_top.yaml")
    interpreted = casmech.joint_space(model)
    rng = np.random.default_rng(5)
    q, v, tau = _state(interpreted, rng)

    cold = casmech.joint_space(casmech.compile(model))  # mode auto, an empty cache
    found = _outputs(cold, q, v, tau)
    assert all(cold[name].is_a("SXFunction") for name in FUNCTIONS)
    assert cache.entries(root) == [] and cache.unfinished(root) == []  # nothing built
    for a, b in zip(found, _outputs(interpreted, q, v, tau), strict=True):
        np.testing.assert_array_equal(a, b)  # the same SX functions

    CompiledSpace(lower(model)).evaluated["forward_dynamics"]  # its library alone, built
    built = cache.entries(root)
    warm = casmech.joint_space(casmech.compile(model))  # auto again: a new bundle, a new space
    assert not warm["forward_dynamics"].is_a("SXFunction")  # the library's, with d fixed
    assert warm["mass_matrix"].is_a("SXFunction")  # not in the cache: interpreted
    found = _outputs(warm, q, v, tau)
    assert cache.entries(root) == built and cache.unfinished(root) == []
    for a, b in zip(found, _outputs(interpreted, q, v, tau), strict=True):
        # the compiled forward dynamics reads the constants from the data input instead of
        # folding them in: roundoff of O(1) quantities
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def test_an_auto_space_looks_again_once_its_bundle_is_handed_over(toolchain, tmp_path,
                                                                   monkeypatch):
    from casmech.backends.joint_space_library import CompiledSpace
    from casmech.model.lower import lower

    monkeypatch.setenv("CASMECH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("CASMECH_BACKGROUND_BUILD", "0")
    model = casmech.load(MODELS / "heavy_top.yaml")

    class Handover:  # an auto miss's build (backends.handover), done once `done` holds it
        done = None

        def ready(self):
            return self.done

    functions = casmech.compile(model)
    functions = type(functions)(**{**vars(functions), "handover": Handover()})
    before = casmech.joint_space(functions)
    assert before["forward_dynamics"].is_a("SXFunction")  # an empty cache
    CompiledSpace(lower(model)).evaluated["forward_dynamics"]  # its library, built since
    assert casmech.joint_space(functions) is before  # kept: the build is not done
    Handover.done = casmech.compile(model, "interpreted")  # the bundle handed over
    after = casmech.joint_space(functions)
    assert after is not before and not after["forward_dynamics"].is_a("SXFunction")
