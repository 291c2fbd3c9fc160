"""optimal/system.py: the functions of theta are the model's at every theta. At values away
from the model's (each parameter moved by a few per cent), each function equals a fresh
numeric build (equations.functions over the plain lowering) of the model loaded with those
values, so d(theta) is exact there, geometry included; and the `--set` values the model was
loaded with are kept."""

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest

import casmech
from casmech.core import euler
from casmech.equations.functions import build_functions
from casmech.errors import UsageError
from casmech.model.lower import lower
from casmech.optimal.system import BUNDLE, parametric_system
from tests.conftest import MODELS
from tests.integration.optimal.test_sensitivity import TILTED

NAMES = ["m2", "J", "g", "k", "c", "w0", "tilt"]  # masses, inertia, gravity, forces, an axis


def _evaluate(function: ca.Function, args) -> list[np.ndarray]:
    return [np.array(v.full()) for v in function.call([ca.DM(a) for a in args])]


def _start(ir, name: str, q=None) -> np.ndarray:
    """The file's pose (initial_guess) or its velocities at q (file_velocities) of a numeric
    IR: p_dot = 1/2 E(p)^T omega."""
    if name == "initial_guess":
        return np.concatenate([b.r0 for b in ir.bodies] + [b.p0 for b in ir.bodies])
    nb = len(ir.bodies)
    spins = [0.5 * euler.numeric(euler.e_matrix, q[3 * nb + 4 * k:3 * nb + 4 * k + 4]).T
             @ b.omega0 for k, b in enumerate(ir.bodies)]
    return np.concatenate([b.r_dot0 for b in ir.bodies] + spins)


def _same_as_fresh(load, names, moved):
    """Every function of the parametric system at `moved` against a fresh build of the model
    loaded at those values."""
    system = parametric_system(load({}), names)
    theta = np.array([moved.get(n, v) for n, v in zip(names, system.values, strict=True)])
    fresh_ir = lower(load({n: repr(float(v)) for n, v in moved.items()}))
    fresh = build_functions(fresh_ir)
    rng = np.random.default_rng(5)
    for name in (*BUNDLE, "file_velocities", "initial_guess"):
        function = system[name]
        args = [rng.standard_normal(function.sparsity_in(k).shape)
                for k in range(function.n_in() - 1)]
        got = _evaluate(function, [*args, theta])
        want = fresh.evaluate(name, *args) if name in BUNDLE else \
            [_start(fresh_ir, name, *(a.ravel() for a in args))]
        for a, b in zip(got, want, strict=True):
            # the same formulas on the same numbers, d(theta) by CasADi, the fresh lowering by
            # NumPy: round-off, relative to the largest entry
            scale = 1 + np.abs(b).max(initial=0)
            np.testing.assert_allclose(a, np.reshape(b, a.shape), rtol=0, atol=1e-12 * scale,
                                       err_msg=name)


def test_functions_at_moved_values_are_fresh_builds():
    def load(overrides):
        return casmech.loads(TILTED, overrides=overrides)

    rng = np.random.default_rng(11)
    model = load({})
    moved = {n: model.parameters[n] * (1 + 0.05 * rng.uniform(-1, 1)) for n in NAMES}
    _same_as_fresh(load, NAMES, moved)


@pytest.mark.parametrize("name, names", [("four_bar.yaml", ["a", "c", "d"]),
                                         ("chain_repeat.yaml", ["L", "w0"]),
                                         ("quadruped_legs.yaml", ["a", "front_left.L1"])])
def test_geometry_and_composed_models_at_moved_values(name, names):
    """Link lengths that move every pose of a closed loop (the file's pose is computed from
    them); a composed chain's link length and spin; an instance's own parameter."""
    def load(overrides):
        return casmech.load(MODELS / name, overrides)

    model = load({})
    moved = {n: model.parameters[n] * 1.03 for n in names}
    _same_as_fresh(load, names, moved)


def test_overrides_are_kept():
    """A model loaded with --set values: its system is at those values, and a parameter set on
    the command line keeps its value when one it was computed from moves (four_bar.yaml's Cx
    follows d in the file; with --set Cx=1.7 it stays 1.7)."""
    sets = {"Cx": "1.7", "b": "2.1"}

    def load(overrides):
        return casmech.load(MODELS / "four_bar.yaml", {**sets, **overrides})

    system = parametric_system(load({}), ["d"])
    assert system.values[0] == 2.0
    _same_as_fresh(load, ["d"], {"d": 2.05})


def test_velocity_offsets():
    """`<body>.wz` adds to the body's angular velocity in the file: the same as moving w0,
    which the file writes there."""
    model = casmech.loads(TILTED)
    system = parametric_system(model, ["upper.wz", "w0"])
    q = lower(model).bodies
    args = np.concatenate([b.r0 for b in q] + [b.p0 for b in q])
    both = [_evaluate(system["file_velocities"], [args, theta])[0]
            for theta in ([0.3, 1.2], [0.0, 1.5])]
    # the same sum: round-off
    np.testing.assert_allclose(both[0], both[1], rtol=0, atol=1e-15)


def test_usage_errors():
    model = casmech.loads(TILTED)
    with pytest.raises(UsageError, match="neither a parameter"):
        parametric_system(model, ["nope"])
    edited = replace(model, parameters={**model.parameters, "k": 31.0})
    with pytest.raises(UsageError, match=r"<string>:\d+:\d+: parameter 'tilt' cannot be a "
                                         r"variable of this model: .* gives k = 30.0, not 31.0"):
        parametric_system(edited, ["tilt"])
