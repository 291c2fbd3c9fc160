"""The lowering over symbolic parameters: every number of the IR of a model loaded with some
parameters symbolic (schema.load_model_text's `symbolic`) carries its expression, and its
derivative by CasADi's AD agrees with sixth-order central differences of the plain lowering
(the numeric pipeline re-loaded at moved values, --set style: schema and model.lower on
floats) to 1e-10, on every model in models/, for a few parameters of each (geometry among
them). The model data d(theta) of model.parametric is checked the same way."""

from dataclasses import fields, is_dataclass
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from casmech.core import traced
from casmech.model import parametric
from casmech.model.lower import lower
from casmech.schema import load_model
from tests.conftest import ROOT

MODELS = ROOT / "models"
SIXTH = ((1, 3 / 4), (2, -3 / 20), (3, 1 / 60))  # (k, weight of f(x + k h) - f(x - k h))
STEP = 1e-3  # relative step of the differences (h^6 truncation: far below their round-off)
SKIPPED = frozenset({"file", "text", "source", "sources", "parameters"})

# model -> parameters (a few per model: lengths, joint points, axes and angles, initial poses
# and velocities, masses, inertias, force and driver constants; composed models' included)
PARAMETERS = {
    "bouncing_ball.yaml": ["r", "h", "m"],
    "bricard.yaml": ["L", "m", "s"],
    "bushing_mount.yaml": ["a", "kz", "kt", "roll0"],
    "cardan_shaft.yaml": ["b", "Ls", "omega"],
    "cart_pole.yaml": ["L", "m_pole", "theta0", "cart_h"],
    "chain_repeat.yaml": ["L", "w0", "m"],
    "double_pendulum.yaml": ["L1", "L2", "theta1", "theta2"],
    "estimate_pendulum.yaml": ["L", "a0", "m"],
    "flyball_governor.yaml": ["l", "alpha0", "d", "c"],
    "four_bar.yaml": ["a", "c", "d"],
    "heavy_top.yaml": ["h", "theta0", "omega3", "l"],
    "me751_pendulum.yaml": ["L", "w"],
    "motor_crank.yaml": ["a", "b", "t_ramp"],
    "ocp_arm3d.yaml": ["L1", "L2", "h0"],
    "ocp_cart_pole_swing_up.yaml": ["L", "mp"],
    "ocp_double_pendulum_swing_up.yaml": ["L"],
    "ocp_pendulum_swing_up.yaml": ["L", "c"],
    "quadruped_legs.yaml": ["a", "b", "m1", "knee_amplitude", "front_left.L1"],
    "robot_arm_3r.yaml": ["L1", "A2", "h0"],
    "scotch_yoke.yaml": ["r", "x0"],
    "slider_crank.yaml": ["a", "b"],
    "spatial_rsur.yaml": ["a", "c", "Dy"],
    "table_driver.yaml": ["r_cam", "preload", "k"],
    "triple_pendulum.yaml": ["L1", "theta2", "theta3"],
    "user_force_pendulum.yaml": ["L", "omega0", "k3"],
    "validation/andrews_squeezer.yaml": ["xa", "rr", "c0"],
    "validation/iftomm_a01_pendulum.yaml": ["L", "m"],
    "validation/iftomm_a02_four_bar_N2.yaml": ["L", "w"],
    "validation/rotspring_case01.yaml": ["k", "c"],
    "validation/transpring_case01.yaml": ["k", "h"],
}


def numbers(value, found: list) -> None:
    """Every number of an IR in walk order (traced numbers as they are)."""
    if isinstance(value, traced.Traced):
        found.append(value)
    elif isinstance(value, (bool, str, int, range, type(None))):
        return
    elif isinstance(value, (float, np.floating)):
        found.append(float(value))
    elif isinstance(value, np.ndarray):
        found.extend(np.asarray(value, object).ravel().tolist())
    elif hasattr(value, "text") and hasattr(value, "root"):
        return
    elif is_dataclass(value):
        for item in fields(value):
            if item.name not in SKIPPED:
                numbers(getattr(value, item.name), found)
    elif hasattr(value, "items"):
        for item in value.values():
            numbers(item, found)
    elif isinstance(value, (tuple, list)):
        for item in value:
            numbers(item, found)


def flat(ir) -> list:
    found: list = []
    numbers(ir, found)
    return found


def plain(path: Path, overrides: dict) -> np.ndarray:
    return np.array([float(x) for x in flat(lower(load_model(path, overrides)))])


def differences(path: Path, name: str, value: float) -> np.ndarray:
    """d (every number of the plain lowering) / d name, sixth-order central differences."""
    h = STEP * (abs(value) or 1.0)
    ends = {k: plain(path, {name: repr(value + k * h)}) for k in (-3, -2, -1, 1, 2, 3)}
    return sum(w * (ends[k] - ends[-k]) for k, w in SIXTH) / h


def jacobian(model, names) -> tuple[np.ndarray, np.ndarray]:
    """(values, d values / d theta by AD) of every number of the traced lowering."""
    found = flat(lower(model))
    theta = ca.vertcat(*(model.symbols[n] for n in names))
    expressions = ca.vertcat(*(traced.expression(x) if isinstance(x, traced.Traced)
                               else ca.SX(float(x)) for x in found))
    evaluate = ca.Function("j", [theta], [ca.jacobian(expressions, theta)])
    at = [traced.value(model.parameters[n]) for n in names]
    return np.array([traced.value(x) for x in found]), np.array(evaluate(at).full())


@pytest.mark.parametrize("name", sorted(PARAMETERS))
def test_lowering_derivatives_against_central_differences(name):
    path = MODELS / name
    names = PARAMETERS[name]
    model = load_model(path, symbolic=names)
    values, ad = jacobian(model, names)
    reference = plain(path, {})
    # the traced values are the plain lowering's (the same float operations; an object
    # array's sums may add in another order: a few ulps)
    np.testing.assert_allclose(values, reference, rtol=1e-14, atol=1e-15)
    for j, parameter in enumerate(names):
        fd = differences(path, parameter, float(traced.value(model.parameters[parameter])))
        # sixth-order differences at h = 1e-3 relative: truncation ~h^6, round-off
        # ~1e-16 |x| / h = 1e-13 |x|; the bound 1e-10 (relative to 1 + |x|)
        scale = 1 + np.abs(values)
        np.testing.assert_allclose(ad[:, j] / scale, fd / scale, rtol=0, atol=1e-10,
                                   err_msg=f"d/d{parameter}")


@pytest.mark.parametrize("name", ["estimate_pendulum.yaml", "chain_repeat.yaml",
                                  "four_bar.yaml"])
def test_model_data_function_against_central_differences(name):
    """d(theta) of model.parametric (the entries of d, traced or not): its values at theta
    are the split's, its Jacobian agrees with the differences of the traced lowering's own
    split values (each re-loaded at moved values: the same structure)."""
    path = MODELS / name
    names = PARAMETERS[name]
    model = load_model(path, symbolic=names)
    split = parametric.split(lower(model))
    theta = ca.vertcat(*(model.symbols[n] for n in names))
    data = split.data_function(theta)
    at = np.array([traced.value(model.parameters[n]) for n in names], float)
    # CasADi evaluates the expressions, NumPy computed the values: round-off
    np.testing.assert_allclose(np.array(data(at).full()).ravel(), split.values, rtol=1e-14,
                               atol=1e-15)
    ad = np.array(ca.Function("j", [theta], [ca.jacobian(split.expressions, theta)])(at).full())
    for j, parameter in enumerate(names):
        h = STEP * (abs(at[j]) or 1.0)
        ends = {k: parametric.split(lower(load_model(
            path, {parameter: repr(float(at[j] + k * h))}, symbolic=names))).values
            for k in (-3, -2, -1, 1, 2, 3)}
        fd = sum(w * (ends[k] - ends[-k]) for k, w in SIXTH) / h
        # as above
        scale = 1 + np.abs(split.values)
        np.testing.assert_allclose(ad[:, j] / scale, fd / scale, rtol=0, atol=1e-10)
