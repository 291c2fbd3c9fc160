"""Statics (runtime/statics.py) against closed forms (issue 17 item 1 'must show')."""

import numpy as np
import pytest
from scipy.optimize import brentq

import casmech
from casmech.errors import AnalysisError, BodyName
from casmech.runtime import statics
from tests.conftest import MODELS
from tests.helpers.statics_models import (
    FREE_BODY,
    RSDA_PENDULUM,
    SPRING_MASS,
    VERTICAL_HINGE,
    G,
    compiled,
    row,
)


def line_of(text: str, needle: str) -> int:
    """1-based line of the text holding needle."""
    return next(n for n, line in enumerate(text.splitlines(), 1) if needle in line)


def rsda_angle(m, length, k):
    """theta > 0 with k theta = m g (L/2) sin(theta) (k < m g L/2)."""
    return brentq(lambda x: k * x - m * G * length / 2 * np.sin(x), 1e-3, np.pi, xtol=1e-15)


# from upright (an unstable equilibrium: left along its mode), from near the answer, and
# from beyond it on the other side
@pytest.mark.parametrize("theta0", [0.0, 1.4, 3.0, -2.5])
def test_rsda_pendulum_angle_matches_closed_form(theta0):
    functions = compiled(RSDA_PENDULUM, theta0=theta0)
    result = casmech.analyze(functions)
    values = row(functions, result)
    theta = 2 * np.arctan2(values["bar.e2"], values["bar.e0"])
    # the equilibrium solves the scalar equation to roundoff (Newton's last steps); 1e-11 rad
    # leaves room for the 1e-12 position tolerance of the constraint projection
    np.testing.assert_allclose(abs(theta), rsda_angle(2.0, 1.0, 5.0), rtol=0, atol=1e-11)
    assert result.metadata["stable"] is True
    assert result.metadata["residual_norm"] <= 1e-10 * 2.0 * G
    assert result.metadata["escapes"] == (1 if theta0 == 0.0 else 0)


def test_rsda_pendulum_rows_are_static_and_pivot_carries_the_weight():
    functions = compiled(RSDA_PENDULUM, theta0=1.0)
    values = row(functions, casmech.analyze(functions))
    for column in ("vx", "vy", "vz", "wx", "wy", "wz", "ax", "ay", "az", "alphax", "alphay",
                   "alphaz"):
        assert values[f"bar.{column}"] == 0.0
    # the pivot carries the whole weight (the rsda only a torque about the hinge axis):
    # relative 1e-10 of m g, a few roundoffs of the Newton solution
    np.testing.assert_allclose(values["pivot.fz"], 2.0 * G, rtol=1e-10, atol=1e-10)
    for column in ("pivot.fx", "pivot.fy", "pivot.tx", "pivot.ty", "pivot.tz"):
        np.testing.assert_allclose(values[column], 0.0, rtol=0, atol=1e-9)


def test_bushing_mount_sags_by_weight_over_stiffness():
    model = casmech.load(MODELS / "bushing_mount.yaml")
    functions = casmech.compile(model)
    values = row(functions, casmech.analyze(functions, "statics"))
    m, kz, h = (model.parameters[name] for name in ("m", "kz", "h"))
    # four mounts in parallel: m g / (4 kz) = 0.49 mm, linear in the bushing; 1e-12 m is
    # roundoff on the 0.15 m position
    np.testing.assert_allclose(values["block.z"], h / 2 - m * G / (4 * kz), rtol=0, atol=1e-12)
    for column in ("block.x", "block.y", "block.e1", "block.e2", "block.e3"):
        np.testing.assert_allclose(values[column], 0.0, rtol=0, atol=1e-12)


def test_spring_deflection_and_slide_reactions():
    functions = compiled(SPRING_MASS)
    result = casmech.analyze(functions, "statics")
    values = row(functions, result)
    m, k, p = 3.0, 120.0, 6.0
    # the push p stretches the spring by p / k; 1e-12 m: roundoff on 1 m
    np.testing.assert_allclose(values["block.x"], 1.0 + p / k, rtol=0, atol=1e-12)
    # the slide carries the weight (not the push, which the spring takes): rtol 1e-10 of m g
    np.testing.assert_allclose(values["slide.fz"], m * G, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(values["slide.fx"], 0.0, rtol=0, atol=1e-9)


# from the file's 90 deg, from both rods upright and from one upright (unstable equilibria,
# left along their unstable modes), and from folded poses
@pytest.mark.parametrize("start", [{}, {"theta1": "pi", "theta2": "pi"},
                                   {"theta1": "0", "theta2": "pi"},
                                   {"theta1": "3", "theta2": "-3"}])
def test_double_pendulum_joints_carry_the_weights_below_them(start):
    model = casmech.load(MODELS / "double_pendulum.yaml", start)
    functions = casmech.compile(model)
    result = casmech.analyze(functions, "statics")
    values = row(functions, result)
    m1, m2, l1, l2 = (model.parameters[name] for name in ("m1", "m2", "L1", "L2"))
    # hanging straight down (1e-12 m: roundoff); pivot carries both rods, elbow the lower
    np.testing.assert_allclose([values["rod1.x"], values["rod2.x"]], 0.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose([values["rod1.z"], values["rod2.z"]], [-l1 / 2, -l1 - l2 / 2],
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose([values["pivot.fz"], values["elbow.fz"]], [(m1 + m2) * G, m2 * G],
                               rtol=1e-10, atol=1e-10)


def test_free_body_has_no_equilibrium_and_is_named():
    functions = compiled(FREE_BODY)
    with pytest.raises(AnalysisError) as caught:
        casmech.analyze(functions)
    joints = caught.value.context.joints
    assert [name for name, _, _ in joints] == ["ball"]
    assert isinstance(joints[0][0], BodyName)
    assert joints[0][1].line == line_of(FREE_BODY, "name: ball")
    assert caught.value.exit_code == 3


def test_zero_stiffness_dof_names_its_joint_and_keeps_the_row():
    functions = compiled(VERTICAL_HINGE)
    with pytest.raises(AnalysisError) as caught:
        casmech.analyze(functions)
    assert "not unique" in str(caught.value)
    (name, source, share), = caught.value.context.joints
    assert (name, source.line, share) == ("hinge", line_of(VERTICAL_HINGE, "name: hinge"), 1.0)
    assert len(caught.value.partial) == 1  # the balanced pose found is kept


def test_cli_statics_exit_3_names_the_body(tmp_path, capsys):
    from casmech.cli import main

    path = tmp_path / "free.yaml"
    path.write_text(FREE_BODY)
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 3
    assert f"{path}:{line_of(FREE_BODY, 'name: ball')}:5: body 'ball'" in capsys.readouterr().err


def test_cli_analysis_statics_overrides_the_model(tmp_path):
    from casmech.cli import main
    from casmech.io.csv import read_csv
    from casmech.io.metadata import read_json

    assert main(["run", str(MODELS / "double_pendulum.yaml"), "--analysis", "statics",
                 "--out", str(tmp_path)]) == 0
    names, values = read_csv(tmp_path / "results.csv")
    assert values.shape == (1, len(names))
    metadata = read_json(tmp_path / "metadata.json")
    assert metadata["analysis"]["type"] == "statics"
    assert metadata["result"]["residual_norm"] <= 1e-10 * 2 * G


def test_null_space_is_orthonormal_and_annihilated():
    rng = np.random.default_rng(7)
    phi_q = rng.standard_normal((4, 7))
    phi_q = np.vstack([phi_q, phi_q[0] + 2 * phi_q[1] + 1e-12])  # redundant (to 1e-12)
    basis = statics.null_space(phi_q)
    assert basis.shape == (7, 3)
    # orthonormal and in the null space to roundoff of O(1) entries
    np.testing.assert_allclose(basis.T @ basis, np.eye(3), rtol=0, atol=1e-13)
    # the fifth row is a combination of two others to 1e-12: the basis is annihilated by all
    # rows to that size (the rank cut, 1e-9, counts the row redundant)
    np.testing.assert_allclose(phi_q @ basis, 0.0, rtol=0, atol=1e-11)


def test_cli_zero_stiffness_keeps_the_row_with_status_failed(tmp_path, capsys):
    from casmech.cli import main
    from casmech.io.csv import read_csv
    from casmech.io.metadata import read_json

    path = tmp_path / "hinge.yaml"
    path.write_text(VERTICAL_HINGE)
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 3
    assert "joint 'hinge'" in capsys.readouterr().err
    _, values = read_csv(tmp_path / "out" / "results.csv")
    assert values.shape[0] == 1
    metadata = read_json(tmp_path / "out" / "metadata.json")
    assert metadata["status"] == "failed" and "not unique" in metadata["error"]
