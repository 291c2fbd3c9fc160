"""Bad Adams decks give one located error (file:line:col, expected, hint); what is not
translated gives a warning naming its line and statement, and the rest still imports."""

import numpy as np
import pytest

import casmech
from casmech.errors import ModelError
from casmech.importers import import_file

GOOD = """pendulum
UNITS/, LENGTH = METER
PART/1, GROUND
MARKER/101, PART = 1
PART/2, MASS = 1, CM = 201, IP = 0.04, 0.1, 0.1
MARKER/201, PART = 2, QP = 2, 0, 0
MARKER/202, PART = 2
JOINT/1, REVOLUTE
, I = 101, J = 202
ACCGRAV/, KGRAV = -9.80665
END
"""


def write(tmp_path, text, name="deck.adm"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_good_deck_imports_without_warnings(tmp_path):
    text, warnings = import_file(write(tmp_path, GOOD))
    assert warnings == []
    assert casmech.loads(text).joints[0].name == "joint_1"


# (what is changed, replacement, code, line, column of the offending text)
BAD = {
    "unknown marker": (", I = 101, J = 202", ", I = 101, J = 299", "E300", 9, 16),
    "not a number": ("QP = 2, 0, 0", "QP = 2, zero, 0", "E102", 6, 31),
    "degrees on a length": ("QP = 2, 0, 0", "QP = 2D, 0, 0", "E102", 6, 28),
    "wrong count": ("QP = 2, 0, 0", "QP = 2, 0", "E102", 6, 23),
    "missing J": (", I = 101, J = 202", ", I = 101", "E100", 8, 1),
    "unknown part": ("MARKER/202, PART = 2", "MARKER/202, PART = 7", "E300", 7, 20),
    "not a statement": ("ACCGRAV/, KGRAV", "ACCGRAV KGRAV", "E102", 10, 1),
    "continuation first": ("UNITS/, LENGTH = METER", ", LENGTH = METER", "E102", 2, 1),
    "no mass": ("MASS = 1, CM", "CM", "E100", 5, 9),
}


@pytest.mark.parametrize("case", BAD)
def test_bad_deck_gives_located_error(tmp_path, case):
    old, new, code, line, col = BAD[case]
    assert old in GOOD
    path = write(tmp_path, GOOD.replace(old, new, 1))
    with pytest.raises(ModelError) as raised:
        import_file(path)
    (diagnostic,) = raised.value.diagnostics
    assert (diagnostic.code, diagnostic.source.line, diagnostic.source.col) == (code, line, col)
    assert diagnostic.source.file == str(path)
    assert diagnostic.expected and diagnostic.hint
    assert diagnostic.format().startswith(f"{path}:{line}:{col}: error[{code}]")


def test_untranslated_statements_warn_with_their_line(tmp_path):
    extra = ("FRICTION/5, JOINT = 1, MU_STATIC = 0.1\n"
             "SFORCE/3, TRANSLATIONAL, I = 201, J = 101\n"
             ", FUNCTION = -10*DM(201,101)**2\n"
             "MARKER/203, PART = 2, REULER = 1.5, 0, 0\n")
    path = write(tmp_path, GOOD.replace("END\n", extra + "END\n"))
    text, warnings = import_file(path)
    found = {(w.path, w.source.line, w.code) for w in warnings}
    assert ("FRICTION/5", 11, "E101") in found  # unknown statement
    assert ("SFORCE/3", 13, "E103") in found  # the FUNCTION is not linear in DM
    assert ("MARKER/203", 14, "E103") in found  # a bare angle is radians: worth a warning
    assert all(w.severity == "warning" for w in warnings)
    model = casmech.loads(text)
    assert model.forces == ()  # the SFORCE was left out, the rest imported
    assert "# line 11: FRICTION/5, JOINT = 1, MU_STATIC = 0.1" in text


def test_radian_angles_without_suffix_are_radians(tmp_path):
    """REULER = 1.5707963267948966 (radians, no suffix) equals REULER = 90D."""
    radians = GOOD.replace("QP = 2, 0, 0", "QP = 2, 0, 0, REULER = 1.5707963267948966, 0, 0")
    degrees = GOOD.replace("QP = 2, 0, 0", "QP = 2, 0, 0, REULER = 90D, 0, 0")
    a = casmech.loads(import_file(write(tmp_path, radians, "r.adm"))[0]).bodies[0]
    b = casmech.loads(import_file(write(tmp_path, degrees, "d.adm"))[0]).bodies[0]
    # the two spellings differ by the roundoff of pi/2 written to 17 digits
    np.testing.assert_allclose(a.euler_parameters, b.euler_parameters, rtol=0, atol=1e-15)


def test_clashing_view_names_stay_unique(tmp_path):
    """Adams/View names can repeat across kinds; casmech names are unique across bodies,
    joints and forces, so the second falls back to its statement id."""
    deck = GOOD.replace("JOINT/1, REVOLUTE", "!  adams_view_name='PART_2'\nJOINT/1, REVOLUTE")
    deck = deck.replace("PART/2, MASS", "!  adams_view_name='PART_2'\nPART/2, MASS")
    model = casmech.loads(import_file(write(tmp_path, deck))[0])
    assert (model.bodies[0].name, model.joints[0].name) == ("part_2", "joint_1")
