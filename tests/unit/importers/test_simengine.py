"""simEngine3D (ME751) model/acf JSON -> casmech, on the course's driven pendulum.

tests/data/me751_pendulum.mdl is the ME751 pendulum written in the course's format: a
4 m bar (L = 2, its half length), revolute at the origin about global x made of three CD and two
DP1 rows, and the driver DP1 y'.(-Z) = cos(theta + pi/2), theta(t) = pi/4 cos(2t). Checked
against the closed form of its motion and against models/me751_pendulum.yaml (the same
mechanism written by hand as a casmech revolute with an angle driver).
"""

import json

import numpy as np
import pytest
import yaml

import casmech
from casmech.errors import ModelError
from casmech.importers import import_file
from tests.conftest import MODELS, run_model
from tests.helpers.importers import DATA, imported, run

MDL = DATA / "me751_pendulum.mdl"
SAMPLE = json.loads(MDL.read_text())
MOTION = ("x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz", "ax", "ay", "az",
          "alphax", "alphay", "alphaz")


def write(tmp_path, data, name="model.mdl"):
    path = tmp_path / name
    path.write_text(json.dumps(data, indent=4))
    return path


def kinematics(path, t_end=2.0):
    _, warnings, functions = imported(path)
    return warnings, run(functions, analysis="kinematics", t_end=t_end, output_step=0.01)


def test_sample_imports_with_its_comments_and_acf_settings():
    text, warnings = import_file(MDL)
    model = casmech.loads(text)
    assert text.startswith("# Imported by `casmech import` from the simEngine3D model "
                           "me751_pendulum.mdl and me751_pendulum.acf.")
    for note in (SAMPLE["comment"], SAMPLE["constraints"][5]["comment"]):
        assert f"# {note}" in text
    assert (model.analysis.type, model.analysis.t_end, model.analysis.output_step) == \
        ("kinematics", 10.0, 0.01)
    assert len(model.joints) == 6 and model.joints[5].name == "driver"
    # one warning per derivative string, at its line
    lines = MDL.read_text().splitlines()
    assert len(warnings) == 12
    for warning in warnings:
        key = warning.path.split(".")[-1]
        assert key in ("f_dot", "f_ddot") and f'"{key}"' in lines[warning.source.line - 1]


def test_acf_names_the_same_model():
    assert import_file(DATA / "me751_pendulum.acf")[0] == import_file(MDL)[0]


def test_pendulum_motion_matches_closed_form_and_hand_written_model():
    _, table = kinematics(MDL)
    t = table["t"]
    theta = np.pi / 4 * np.cos(2 * t)
    theta_dot = -np.pi / 2 * np.sin(2 * t)
    exact = np.column_stack([0 * t, 2 * np.sin(theta), -2 * np.cos(theta)])
    ours = np.column_stack([table[f"pendulum.{c}"] for c in "xyz"])
    # Newton on the constraints to ~1e-12 at every output time (measured 1.5e-12)
    np.testing.assert_allclose(ours, exact, rtol=0, atol=1e-9)
    np.testing.assert_allclose(table["pendulum.wx"], theta_dot, rtol=0, atol=1e-9)  # same
    _, hand = run_model(MODELS / "me751_pendulum.yaml", analysis="kinematics", t_end=2.0,
                        output_step=0.01)
    for column in MOTION:
        # same motion through different constraint rows: measured <= 4e-12
        np.testing.assert_allclose(table[f"pendulum.{column}"], hand[f"bar.{column}"],
                                   rtol=0, atol=1e-9, err_msg=column)


def test_course_rounded_p_is_normalised_with_a_warning(tmp_path):
    """The course files write p to 4 digits: normalised (warning), the same motion."""
    data = json.loads(MDL.read_text())
    data["bodies"][1]["p"] = [0.6533, 0.2706, 0.6533, 0.2706]
    warnings, table = kinematics(write(tmp_path, data), t_end=0.5)
    (warning,) = [w for w in warnings if w.path == "bodies[1].p"]
    assert "normalised" in warning.message and warning.source.line > 1
    _, exact = kinematics(MDL, t_end=0.5)
    # assembly solves the constraints from the rounded pose: same positions to Newton's 1e-12
    np.testing.assert_allclose(table.values, exact.values, rtol=0, atol=1e-9)


def test_composite_revolute_gives_the_same_motion(tmp_path):
    data = json.loads(MDL.read_text())
    data["constraints"] = [{"name": "pivot", "type": "revolute", "body_i": 1, "body_j": 0,
                            "s_bar_p_i": [-2, 0, 0], "s_bar_q_j": [0, 0, 0],
                            "a_bar_i": [0, 0, 1]}, data["constraints"][5]]
    _, table = kinematics(write(tmp_path, data))
    _, rows = kinematics(MDL)
    for column in MOTION:
        # the same joint as a composite: measured <= 1e-12
        np.testing.assert_allclose(table[f"pendulum.{column}"], rows[f"pendulum.{column}"],
                                   rtol=0, atol=1e-9, err_msg=column)


def line_of(path, text):
    return next(k for k, line in enumerate(path.read_text().splitlines(), 1) if text in line)


def test_bad_json_is_located(tmp_path):
    path = tmp_path / "broken.mdl"
    path.write_text(MDL.read_text().replace('"mass": 78,', '"mass": 78'))
    with pytest.raises(ModelError) as raised:
        import_file(path)
    (diagnostic,) = raised.value.diagnostics
    assert diagnostic.code == "E102" and diagnostic.expected and diagnostic.hint
    # json reports the first token after the missing comma: the next key's line
    assert diagnostic.source.line == line_of(path, '"jbar"')


@pytest.mark.parametrize("change, code, where", [
    (lambda d: d["constraints"][2].update(body_j=7), "E300", '"body_j": 7'),
    (lambda d: d["constraints"][5].update(f="cosh2(t)"), "E200", '"f": "cosh2(t)"'),
    (lambda d: d["bodies"][1].update(r=[0, 1]), "E102", '"r": ['),
    (lambda d: d["bodies"][1].pop("mass"), "E100", '"name": "pendulum"'),
])
def test_bad_model_errors_point_at_the_value(tmp_path, change, code, where):
    data = json.loads(MDL.read_text())
    change(data)
    path = write(tmp_path, data)
    with pytest.raises(ModelError) as raised:
        import_file(path)
    (diagnostic,) = raised.value.diagnostics
    assert diagnostic.code == code and diagnostic.expected
    if code != "E100":  # a missing key is located at its object
        assert diagnostic.source.line == line_of(path, where)


def test_unknown_keys_warn_and_are_left_out(tmp_path):
    data = json.loads(MDL.read_text())
    data["bodies"][1]["color"] = "red"
    path = write(tmp_path, data)
    _, warnings = import_file(path)
    (warning,) = [w for w in warnings if w.path == "bodies[1].color"]
    assert warning.code == "E101" and warning.source.line == line_of(path, '"color"')


def test_quoted_body_ids_are_read(tmp_path):
    """Some course files quote the ids ("body2": "2"); the model is the same."""
    data = json.loads(MDL.read_text())
    for row in data["constraints"]:
        row["body_j"] = str(row["body_j"])
    (tmp_path / "quoted").mkdir()
    quoted = yaml.safe_load(import_file(write(tmp_path / "quoted", data))[0])
    assert quoted == yaml.safe_load(import_file(write(tmp_path, SAMPLE))[0])


def test_acf_errors_are_located(tmp_path):
    acf = tmp_path / "run.acf"
    acf.write_text('{\n    "simulation": "kinematics",\n    "t_end": 1\n}\n')
    with pytest.raises(ModelError) as raised:  # no run.mdl beside it, none named in it
        import_file(acf)
    assert raised.value.diagnostics[0].code == "E300"
    assert raised.value.diagnostics[0].source.file == str(acf)
    (tmp_path / "run.mdl").write_text(MDL.read_text())
    acf.write_text('{\n    "simulation": "quasi-static",\n    "t_end": 1\n}\n')
    with pytest.raises(ModelError) as raised:
        import_file(acf)
    (diagnostic,) = raised.value.diagnostics
    assert (diagnostic.code, diagnostic.source.line) == ("E103", 2)
    assert "kinematics" in diagnostic.expected
