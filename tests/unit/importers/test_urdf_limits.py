"""URDF `<limit lower upper>` imported as the joint's `limit:` stop (importers/urdf_limits.py):
bounds counted from the imported pose, MuJoCo's default softness (time constant 0.02 s,
critical damping) for the inertia the joint moves; checked against the closed-form rest on
the stop of a slider and of a pendulum, and on the Panda of example-robot-data, whose fingers
stay between their limits in a run (and leave them without the stops)."""

from __future__ import annotations

import math
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

import casmech
from casmech.importers.emit import to_yaml
from casmech.importers.urdf import import_urdf
from casmech.importers.urdf_limits import TIME_CONSTANT
from tests.conftest import Table

SLIDER = """<?xml version="1.0"?>
<robot name="slider">
  <link name="base"/>
  <joint name="slide" type="prismatic">
    <parent link="base"/>
    <child link="block"/>
    <axis xyz="0 0 1"/>
    <limit lower="-0.1" upper="0.1" effort="5" velocity="3"/>
  </joint>
  <link name="block">
    <inertial>
      <mass value="2"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>
    </inertial>
  </link>
</robot>
"""
PENDULUM = """<?xml version="1.0"?>
<robot name="pendulum">
  <link name="base"/>
  <joint name="hinge" type="%s">
    <parent link="base"/>
    <child link="rod"/>
    <axis xyz="0 1 0"/>
    <limit lower="%s" upper="%s" effort="5" velocity="3"/>
  </joint>
  <link name="rod">
    <inertial>
      <origin xyz="0 0 -0.5"/>
      <mass value="2"/>
      <inertia ixx="0.17" ixy="0" ixz="0" iyy="0.17" iyz="0" izz="0.001"/>
    </inertial>
  </link>
</robot>
"""


def imported(tmp_path, text: str, **initial):
    path = tmp_path / "robot.urdf"
    path.write_text(text)
    result = import_urdf(path, **initial)
    return result, str(path) + ".yaml"


def run(text: str, file: str, **settings) -> Table:
    functions = casmech.compile(casmech.loads(text, file=file))
    return Table(*casmech.results_table(functions, casmech.analyze(functions, **settings)))


@pytest.mark.parametrize("start", [0.0, 0.05])
def test_a_slider_comes_to_rest_on_its_lower_stop(tmp_path, start):
    """Released under gravity (-z) at `start`, the block falls onto the stop 0.1 m below the
    URDF's zero and rests there pressed in by m g / k = g tau^2 (k = m / tau^2)."""
    result, file = imported(tmp_path, SLIDER, positions={"slide": start})
    [joint] = result.joints
    assert joint.data["limit"]["lower"] == pytest.approx(-0.1 - start, abs=1e-15)
    table = run(to_yaml(result), file, analysis="dynamics", t_end=1.5, rtol=1e-10, atol=1e-12)
    rest = -0.1 - start - 9.81 * TIME_CONSTANT**2
    # critically damped with tau = 0.02 s: settled to e^-50 by t = 1.5 s (the fall takes 0.2 s)
    np.testing.assert_allclose(table["slide.displacement"][-1], rest, rtol=0, atol=1e-9)
    np.testing.assert_allclose(table["slide.limit_force"][-1], 2 * 9.81, rtol=1e-6, atol=0)


def test_a_pendulum_rests_against_its_stop(tmp_path):
    """Hanging is outside [0.5, 1] rad: the stop holds the rod where k (0.5 - a) = m g d
    sin(a), k = I / tau^2 with I = 0.17 + 2 * 0.5^2 about the hinge."""
    result, file = imported(tmp_path, PENDULUM % ("revolute", 0.5, 1.0))
    table = run(to_yaml(result), file, analysis="statics")
    k = 0.67 / TIME_CONSTANT**2
    angle = brentq(lambda a: k * (0.5 - a) - 2 * 9.81 * 0.5 * math.sin(a), 0.0, 0.5)
    np.testing.assert_allclose(table["hinge.angle"][0], angle, rtol=0,
                               atol=1e-9)  # statics to 1e-10 of the loads


@pytest.mark.parametrize(("kind", "lower", "upper", "start", "why"), [
    ("continuous", -1, 1, 0.0, "a continuous joint"),
    ("revolute", -3.5, 3.5, 0.0, "bounds outside (-pi, pi]"),
    ("revolute", -1, 3.0, -0.5, "bounds outside (-pi, pi]"),
    ("revolute", 1, -1, 0.0, "no lower < upper"),
])
def test_limits_no_stop_can_hold_stay_comments(tmp_path, kind, lower, upper, start, why):
    """casmech's angle wraps at +-pi from the imported pose: bounds past it would turn a stop
    into a push the wrong way, so they are not enforced (and said so)."""
    result, _ = imported(tmp_path, PENDULUM % (kind, lower, upper), positions={"hinge": start})
    [joint] = result.joints
    assert "limit" not in joint.data
    assert any(why in comment and "not enforced" in comment for comment in joint.comments)


def panda() -> Path:
    try:
        distribution = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed (pip install example-robot-data)")
    return Path(distribution.locate_file(
        "cmeel.prefix/share/example-robot-data/robots/panda_description/urdf/panda.urdf"))


def test_the_panda_fingers_stay_between_their_limits(tmp_path, monkeypatch):
    """The Panda released under gravity for 1 s: each finger's slide stays within its URDF
    limits [0, 0.04] m but for the stop's give, at most v tau / e + g tau^2 for a critically
    damped stop met at speed v (the largest finger speed of the run) under g; without the
    stops the fingers leave that range by more than ten times as much. The fingers' mimic
    coupler is left out, so that each finger meets its stops on its own (coupled, they stay
    together near 0: tests/validation/importers/test_urdf_mimic.py)."""
    path = panda()
    model = import_urdf(path, output=tmp_path / "panda.yaml")
    model.joints = [joint for joint in model.joints if joint.data["type"] != "coupler"]
    text = to_yaml(model)
    assert text.count("\n    limit:") == 8  # joint6's bounds (-0.0175, 3.7525) pass pi
    monkeypatch.setenv("CASMECH_ALLOWED_DIRS", str(path.parents[1] / "meshes"))
    found = {}
    for stops in (True, False):
        if not stops:
            for joint in model.joints:
                joint.data.pop("limit", None)
            text = to_yaml(model)
        casmech_model = casmech.load(_write(tmp_path, text))
        functions = casmech.compile(casmech_model)
        result = casmech.analyze(functions, "dynamics", t_end=1.0, output_step=0.01)
        found[stops] = Table(*casmech.results_table(functions, result))
    for finger in ("panda_finger_joint1", "panda_finger_joint2"):
        slide = found[True][f"{finger}.displacement"]
        speed = np.abs(found[True][f"{finger}.displacement_dot"]).max()
        give = speed * TIME_CONSTANT / math.e + 9.81 * TIME_CONSTANT**2
        assert slide.min() >= -give and slide.max() <= 0.04 + give
        free = found[False][f"{finger}.displacement"]
        assert max(-free.min(), free.max() - 0.04) > 10 * give


def _write(tmp_path, text: str) -> Path:
    path = tmp_path / "panda.yaml"
    path.write_text(text)
    return path
