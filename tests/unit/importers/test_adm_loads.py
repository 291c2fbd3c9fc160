"""Adams MOTION, BUSHING, VFORCE/VTORQUE/GFORCE imports against closed forms of Adams's
definitions (the motion of I relative to J; the bushing force on I from I's displacement in J's
axes; vector forces along RM's axes)."""

from __future__ import annotations

import numpy as np
import pytest

import casmech
from casmech.importers import import_file
from tests.helpers.importers import imported, run

# a part on a revolute joint about z at the origin, its CM 2 m out along x; no gravity
PENDULUM = """pendulum
UNITS/, LENGTH = METER
PART/1, GROUND
MARKER/101, PART = 1
PART/2, MASS = 1, CM = 201, IP = 0.04, 0.1, 0.1
MARKER/201, PART = 2, QP = 2, 0, 0
MARKER/202, PART = 2
JOINT/1, REVOLUTE
, I = {i}, J = {j}
{motion}
END
"""


def write(tmp_path, text, name="deck.adm"):
    path = tmp_path / name
    path.write_text(text)
    return path


def angle(table) -> np.ndarray:
    return np.arctan2(table["part_2.y"], table["part_2.x"])


@pytest.mark.parametrize("i, j, sign", [(101, 202, -1), (202, 101, 1)])
def test_rotation_motion_is_i_relative_to_j(tmp_path, i, j, sign):
    """Adams turns I relative to J about J's z by f(t) (from the absolute AZ, so f(0) != 0 is
    reached by assembly): the part turns by -f with I on the ground, +f with I on the part."""
    motion = "MOTION/1, JOINT = 1, ROT\n, FUNCTION = 30D*TIME + 10D"
    _, warnings, functions = imported(write(tmp_path, PENDULUM.format(i=i, j=j, motion=motion)))
    assert warnings == []
    table = run(functions, analysis="kinematics", t_end=1.0, output_step=0.25)
    expected = sign * np.deg2rad(30 * table["t"] + 10)
    # assembly and kinematics solve to ~1e-12; the closed form is exact
    np.testing.assert_allclose(angle(table), expected, rtol=0, atol=1e-9)


def test_velocity_motion_and_translation_in_millimetres(tmp_path):
    """VELOCITY mode becomes a speed motor; a TRANSLATION in a deck in millimetres is scaled."""
    motion = "MOTION/1, JOINT = 1, ROTATION, VELOCITY, FUNCTION = 2 + 0*TIME"
    _, _, functions = imported(write(tmp_path, PENDULUM.format(i=101, j=202, motion=motion)))
    table = run(functions, analysis="kinematics", t_end=1.0, output_step=0.25)
    np.testing.assert_allclose(angle(table), np.angle(np.exp(-2j * table["t"])), rtol=0,
                               atol=1e-9)  # as above
    deck = PENDULUM.format(i=101, j=202, motion="MOTION/1, JOINT = 1, TRANS\n"
                           ", FUNCTION = 100*TIME**2").replace(
        "LENGTH = METER", "LENGTH = MILLIMETER").replace("QP = 2, 0, 0", "QP = 2000, 0, 0")
    deck = deck.replace("REVOLUTE", "TRANSLATIONAL")
    _, _, functions = imported(write(tmp_path, deck))
    table = run(functions, analysis="kinematics", t_end=1.0, output_step=0.25)
    # I on the ground: the part slides by -f along z; 100 mm t^2 = 0.1 m t^2 (exact)
    np.testing.assert_allclose(table["part_2.z"], -0.1 * table["t"] ** 2, rtol=0, atol=1e-12)


@pytest.mark.parametrize("motion, words", [
    ("MOTION/1, JOINT = 1, ROTATION, ACCELERATION, FUNCTION = 1", "ACCELERATION motions"),
    ("MOTION/1, JOINT = 1, TRANSLATION, FUNCTION = TIME", "a TRANSLATION motion on a revolute"),
    ("MOTION/1, JOINT = 1, ROTATION, FUNCTION = DX(201, 101)", "reads the state (DX(201, 101))"),
    ("MOTION/1, JOINT = 7, ROTATION, FUNCTION = TIME", "JOINT/7 is not a translated joint"),
    ("MOTION/1, I = 201, J = 101, X, FUNCTION = TIME", "only motions on a JOINT"),
])
def test_motions_not_translated_are_warnings(tmp_path, motion, words):
    path = write(tmp_path, PENDULUM.format(i=101, j=202, motion=motion))
    text, warnings = import_file(path)
    (warning,) = warnings
    assert warning.source.line == 10 and words in warning.message, warning.format()
    assert "driver" not in text and "motor" not in text
    casmech.loads(text)  # the rest still validates


# a free part, its CM at (1, 2, 3), and ground markers: 301 at the CM with axes turned 90 deg
# about z (x -> global y, y -> global -x); 302 at the origin, global axes
FREE = """free part
UNITS/, LENGTH = METER
PART/1, GROUND
MARKER/301, PART = 1, QP = 1, 2, 3, REULER = 90D, 0, 0
MARKER/302, PART = 1
PART/2, MASS = 2, CM = 201, IP = 0.5, 0.6, 0.7, VX = {vx}
MARKER/201, PART = 2, QP = 1, 2, 3
MARKER/202, PART = 2, QP = 1, 2, 3, REULER = 90D, 0, 0
{load}
END
"""


def test_bushing_force_on_i_from_its_displacement_in_j_axes(tmp_path):
    """I on the part, J on the ground turned 90 deg about z: a push along global x deflects
    along J's -y (stiffness ky), the preload FORCE pushes I along J's z (stiffness kz)."""
    m, ky, kz, preload, v = 2.0, 50.0, 200.0, 4.0, 0.3
    load = f"BUSHING/1, I = 202, J = 301, K = 10, {ky}, {kz}, C = 0, 0, 0\n" \
           f", KT = 1, 1, 1, FORCE = 0, 0, {preload}"
    _, warnings, functions = imported(write(tmp_path, FREE.format(vx=v, load=load)))
    assert warnings == []
    table = run(functions, analysis="dynamics", t_end=1.0, output_step=0.1, rtol=1e-10,
                atol=1e-12)
    t = table["t"]
    wy, wz = np.sqrt(ky / m), np.sqrt(kz / m)
    # linear oscillators, integrated at rtol 1e-10: 1e-8 m
    np.testing.assert_allclose(table["part_2.x"], 1 + v / wy * np.sin(wy * t), rtol=0,
                               atol=1e-8)
    np.testing.assert_allclose(table["part_2.z"], 3 + preload / kz * (1 - np.cos(wz * t)),
                               rtol=0, atol=1e-8)
    np.testing.assert_allclose(table["part_2.y"], 2, rtol=0, atol=1e-8)


def test_bushing_markers_apart_is_a_warning(tmp_path):
    load = "BUSHING/1, I = 201, J = 302, K = 1, 1, 1"
    _, warnings = import_file(write(tmp_path, FREE.format(vx=0, load=load)))
    (warning,) = warnings
    assert warning.source.line == 9 and "the I and J markers differ at t = 0" in warning.message


@pytest.mark.parametrize("rm", [301, 202])
def test_gforce_components_along_rm(tmp_path, rm):
    """FX = 2 TIME, FZ = 3 along RM's axes (RM x = global y) on a free part; TZ = 0.5 about
    RM's z = global z. RM on the ground gives global components, RM on the part body ones (the
    part turns about z, so these agree only while it has not turned: t = 0 .. 0.5 with a small
    torque is checked for the force along global z, which both keep)."""
    load = f"GFORCE/1, I = 201, JFLOAT = 302, RM = {rm}\n, FX = 2*TIME\\ FY = 0\\ FZ = 3\\\n" \
           ", TX = 0\\ TY = 0\\ TZ = 0.5"
    text, warnings = import_file(write(tmp_path, FREE.format(vx=0, load=load)))
    assert warnings == []
    functions = casmech.compile(casmech.loads(text))
    table = run(functions, analysis="dynamics", t_end=1.0, output_step=0.25, rtol=1e-10,
                atol=1e-12)
    t, m, izz = table["t"], 2.0, 0.7
    # z: 3 N along global z either way; integrated at rtol 1e-10
    np.testing.assert_allclose(table["part_2.z"], 3 + 3 * t**2 / (2 * m), rtol=0, atol=1e-8)
    turn = 0.5 * t**2 / (2 * izz)  # angle about z
    np.testing.assert_allclose(2 * np.arctan2(table["part_2.e3"], table["part_2.e0"]), turn,
                               rtol=0, atol=1e-8)
    if rm == 301:  # global components: 2t along global y, x untouched
        np.testing.assert_allclose(table["part_2.y"], 2 + t**3 / (3 * m), rtol=0, atol=1e-8)
        np.testing.assert_allclose(table["part_2.x"], 1, rtol=0, atol=1e-8)
    else:  # body components: the force turns with the part (1.2 rad at t = 1)
        assert "frame: body" in text
        assert np.max(np.abs(table["part_2.x"] - 1)) > 1e-3


def test_vforce_and_vtorque_and_what_is_not_translated(tmp_path):
    load = "VFORCE/1, I = 201, JFLOAT = 302, RM = 302, FX = 1\\ FY = 0\\ FZ = 0\n" \
           "VTORQUE/2, I = 201, JFLOAT = 302, RM = 302, TX = 0\\ TY = 0\\ TZ = STEP(TIME,0,0,1,1)"
    text, warnings = import_file(write(tmp_path, FREE.format(vx=0, load=load)))
    assert warnings == []
    forces = casmech.loads(text).forces
    assert [f.type for f in forces] == ["force", "torque"]
    bad = ("VFORCE/1, I = 201, JFLOAT = 202, RM = 302, FX = 1\n"
           "VFORCE/2, I = 201, JFLOAT = 302, RM = 302, FX = VX(201)")
    text, warnings = import_file(write(tmp_path, FREE.format(vx=0, load=bad)))
    assert ["JFLOAT is not on the ground" in w.message for w in warnings] == [True, False]
    assert "reads the state (VX(201))" in warnings[1].message
    assert [w.source.line for w in warnings] == [9, 10]
