"""Adams statements -> casmech values, checked against hand-computed frames and units.

One small deck exercises what the Chrono decks do not: a part placed by QG/REULER, a CM marker
rotated inside it, six IP values (Adams's products are +integral(x y dm): the inertia matrix
holds their negatives), VX and WX (WX is about the CM marker's axes), a marker placed by ZP/XP,
JPRIM INLINE, SPRINGDAMPER and ACCGRAV along y. The same deck in millimetres and grams must give
the same SI model.
"""

import numpy as np
import pytest
import yaml

import casmech
from casmech.importers import import_file
from tests.helpers.importers import DECKS, G, imported, run

DECK = """synthetic deck for the importer tests
UNITS/
, FORCE = NEWTON, MASS = {mass_unit}, LENGTH = {length_unit}, TIME = SECOND
!  ground
PART/1, GROUND
MARKER/11, PART = 1
MARKER/12, PART = 1, QP = {one_l}, 0, 0
MARKER/13, PART = 1, QP = {one_l}, 0, 0, REULER = 0, -90D, 0
!  the body: part frame at (1, 0, 0) turned 90 deg about z
PART/2, MASS = {two_m}, CM = 21
, IP = {three_i}, {four_i}, {five_i}, {p1_i}, {p2_i}, {p3_i}
, QG = {one_l}, 0, 0, REULER = 90D, 0D, 0D
, VX = {half_v}, WX = 2
MARKER/21, PART = 2, QP = {one_l}, 0, 0, REULER = 90D, 0, 0
!  pin marker: z along the part's x axis, x along the part's y axis
MARKER/22, PART = 2, ZP = {one_l}, 0, 0, XP = 0, {one_l}, 0
JOINT/2, REVOLUTE, I = 22, J = 13
JPRIM/1, INLINE, I = 22, J = 11
SPRINGDAMPER/1, TRANSLATIONAL, I = 12, J = 22
, K = {k}, C = {c}, LENGTH = {free_l}
ACCGRAV/, JGRAV = {gravity}
END
"""
SI = dict(mass_unit="KILOGRAM", length_unit="METER", one_l=1, two_m=2, three_i=3, four_i=4,
          five_i=5, p1_i=0.1, p2_i=0.2, p3_i=0.3, half_v=0.5, k=10, c=0.5, free_l=0.7,
          gravity=-9.81)
# millimetre, gram: lengths x1e3, masses x1e3, inertias x1e9, N/mm = 1e3 N/m
MM_G = dict(SI, mass_unit="GRAM", length_unit="MILLIMETER", one_l=1000, two_m=2000,
            three_i=3e9, four_i=4e9, five_i=5e9, p1_i=1e8, p2_i=2e8, p3_i=3e8, half_v=500,
            k=0.01, c=0.0005, free_l=700, gravity=-9810)


@pytest.fixture(scope="module")
def translations(tmp_path_factory):
    out = {}
    for label, values in (("si", SI), ("mm_g", MM_G)):
        path = tmp_path_factory.mktemp(label) / "deck.adm"
        path.write_text(DECK.format(**values))
        text, warnings = import_file(path)
        out[label] = (text, warnings, yaml.safe_load(text))
    return out


def test_deck_translates_completely_and_validates(translations):
    text, warnings, _ = translations["si"]
    assert warnings == []  # every statement and argument of this deck is translated
    model = casmech.loads(text)
    assert [b.name for b in model.bodies] == ["part_2"]
    # revolute (5) + inline (2) rows remove 7 > 6 freedoms: checks the rows exist, not the DOF
    functions = casmech.compile(model)
    assert functions.n_joint_rows == 7
    assert "# pin marker: z along the part's x axis, x along the part's y axis" in text


def test_frames_inertia_and_velocities_match_hand_computation(translations):
    _, _, data = translations["si"]
    body = data["bodies"][0]
    # CM = part origin (1,0,0) + Rz(90) (1,0,0) = (1,1,0); rotation Rz(90) Rz(90) = Rz(180)
    np.testing.assert_allclose(body["position"], [1, 1, 0], rtol=0, atol=1e-15)  # roundoff
    p = np.array(body["orientation"]["euler_parameters"])
    np.testing.assert_allclose(abs(p), [0, 0, 0, 1], rtol=0, atol=1e-15)  # roundoff
    assert body["inertia"] == [3, 4, 5, -0.1, -0.2, -0.3]
    assert body["velocity"] == [0.5, 0, 0]
    # WX = 2 about the CM marker's x axis, which is global -x
    np.testing.assert_allclose(body["angular_velocity"], [-2, 0, 0], rtol=0, atol=1e-15)
    assert data["gravity"] == [0, -9.81, 0]
    revolute, inline_x, inline_y = data["joints"]
    # marker 22: z = Rz(90) (part x) = global y, at the part origin (1, 0, 0)
    assert revolute["at"] == [1, 0, 0] and revolute["axis"] == [0, 1, 0]
    # INLINE: marker 22's origin stays on ground marker 11's z axis: rows along 11's x and y;
    # the point in the CM frame: Rz(180)^T ((1,0,0) - (1,1,0)) = (0, 1, 0)
    assert (inline_x["type"], inline_x["body_i"], inline_x["a_i"]) == ("dp2", "ground",
                                                                       [1, 0, 0])
    assert inline_y["a_i"] == [0, 1, 0] and inline_y["s_j"] == [0, 1, 0]
    spring = data["forces"][0]
    parameters = data["parameters"]
    assert [parameters[spring[key]] for key in ("stiffness", "damping", "free_length")] == \
        [10, 0.5, 0.7]


def leaves(data, path=()):
    """(path, value) of every number or string in nested YAML data."""
    if isinstance(data, dict):
        return [leaf for key, value in data.items() for leaf in leaves(value, (*path, key))]
    if isinstance(data, list):
        return [leaf for k, value in enumerate(data) for leaf in leaves(value, (*path, k))]
    return [(path, data)]


def test_millimetre_gram_deck_gives_the_same_si_model(translations):
    _, _, si = translations["si"]
    _, warnings, mm = translations["mm_g"]
    assert warnings == []
    for section in ("bodies", "joints", "forces"):
        ours, theirs = dict(leaves(mm[section])), dict(leaves(si[section]))
        assert ours.keys() == theirs.keys()
        for path, value in theirs.items():
            if isinstance(value, str):
                assert ours[path] == value, path
            else:
                # unit factors are exact powers of ten: agreement to roundoff
                np.testing.assert_allclose(ours[path], value, rtol=1e-12, atol=1e-15,
                                           err_msg=str(path))
    names = sorted(si["parameters"])
    assert sorted(mm["parameters"]) == names
    # unit factors are exact powers of ten: agreement to roundoff
    np.testing.assert_allclose([mm["parameters"][n] for n in names],
                               [si["parameters"][n] for n in names], rtol=1e-12, atol=0)
    np.testing.assert_allclose(mm["gravity"], si["gravity"], rtol=1e-12, atol=0)  # as above


ROTSPRING = DECKS / "test_RotSpring_Case01.adm"


@pytest.mark.parametrize("i, j, torque_on_bar", [
    (207, 208, -30.0),  # torque -k (AZ - 30 deg) acts on I (ground): the bar gets -30 N m
    (208, 207, 30.0),  # the same with I on the bar (AZ(208, 207) = 0 at t = 0)
])
def test_rotational_sforce_free_angle_sign(tmp_path, i, j, torque_on_bar):
    """SFORCE ROTATIONAL with a free angle: -RTOD*(AZ - 30*DTOR) is 30 N m at t = 0 (AZ = 0)
    on the I marker's part about the J marker's z (global +y). The bar's angular acceleration
    at t = 0 about the pivot (I = 0.1 + 1 * 2^2 = 4.1) adds gravity's 2 m g about +y."""
    text = ROTSPRING.read_text().replace("-0.0*DTOR", "-30.0*DTOR")
    text = text.replace("I = 207\n, J = 208", f"I = {i}\n, J = {j}")
    text = text.replace("az(207,208)", f"az({i},{j})").replace("wz(207,208,208)",
                                                                f"wz({i},{j},{j})")
    path = tmp_path / "rotspring.adm"
    path.write_text(text)
    _, warnings, functions = imported(path)
    assert not [w for w in warnings if w.path.startswith("SFORCE")]
    table = run(functions, analysis="assembly")
    expected = (2 * G + torque_on_bar) / 4.1
    # the equations of motion at t = 0 are solved to roundoff
    np.testing.assert_allclose(table["part_2.alphay"][0], expected, rtol=1e-12, atol=1e-12)
