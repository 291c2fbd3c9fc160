"""casmech export on the command line: what it prints, and the located usage errors it gives
before building anything."""

import pytest

from casmech.cli import main
from tests.helpers.fmu import MODELS, ROOT


def test_it_writes_the_fmu_and_says_what_it_holds(toolchain, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("CASMECH_CFLAGS", "-O0")
    out = tmp_path / "dp.fmu"
    assert main(["export", str(MODELS / "double_pendulum.yaml"), "-o", str(out),
                 "--outputs", "rod2.*,energy", "--set", "m2=2"]) == 0
    printed = capsys.readouterr()
    assert "4 states, 0 inputs, 20 outputs, 7 parameters (4 fixed, 3 tunable)" in printed.out
    from fmpy import read_model_description

    variables = read_model_description(str(out)).modelVariables
    assert [v.name for v in variables if v.causality == "output"][-1] == "energy"
    assert next(float(v.start) for v in variables if v.name == "m2") == 2.0  # --set: the start


def test_what_the_fmu_leaves_out_is_a_note(toolchain, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("CASMECH_CFLAGS", "-O0")
    assert main(["export", str(MODELS / "cardan_shaft.yaml"), "-o",
                 str(tmp_path / "shaft.fmu")]) == 0
    assert "note: the model's analysis is kinematics" in capsys.readouterr().err


@pytest.mark.parametrize("arguments, words", [
    (["-o", "{tmp}/dp.zip"], "an FMU's file name ends in .fmu"),
    (["-o", "{tmp}/dp.fmu", "--outputs", "rod3.x"], "--outputs rod3.x: no results column"),
    (["-o", "{tmp}/dp.fmu", "--outputs", "rod1.q"], "columns of 'rod1': rod1.x"),
    (["-o", "{tmp}/dp.fmu", "--inputs", "pivot.torque"],
     "--inputs pivot.torque: not an effort motor or ocp: control of the model; inputs: none"),
])
def test_mistakes_are_usage_errors(tmp_path, capsys, arguments, words):
    code = main(["export", str(MODELS / "double_pendulum.yaml"),
                 *(a.format(tmp=tmp_path) for a in arguments)])
    assert code == 2
    assert words in capsys.readouterr().err
    assert not list(tmp_path.iterdir())  # nothing written


def test_a_loop_through_a_floating_body_is_refused(tmp_path, capsys):
    text = """
casmech: 1
name: floating_loop
bodies:
  - {name: a, mass: 1, inertia: [0.1, 0.1, 0.1], position: [0, 0, 0]}
  - {name: b, mass: 1, inertia: [0.1, 0.1, 0.1], position: [1, 0, 0]}
joints:
  - {name: ab, type: spherical, body_i: a, body_j: b, at: [0.5, 0, 0]}
  - {name: ba, type: distance, body_i: a, body_j: b, at_i: [0, 0.2, 0], at_j: [1, 0.2, 0]}
analysis: {type: dynamics, t_end: 1}
"""
    model = tmp_path / "floating_loop.yaml"
    model.write_text(text)
    assert main(["export", str(model), "-o", str(tmp_path / "loop.fmu")]) == 2
    assert "a loop closes through a floating body" in capsys.readouterr().err


def test_the_command_is_documented():
    assert "## casmech export" in (ROOT / "docs" / "cli.md").read_text()


def test_a_parameter_named_as_a_column_is_refused(tmp_path, capsys):
    text = (MODELS / "double_pendulum.yaml").read_text().replace(
        "parameters:\n", "parameters:\n  energy: 1.0\n", 1)
    model = tmp_path / "named.yaml"
    model.write_text(text)
    assert main(["export", str(model), "-o", str(tmp_path / "named.fmu")]) == 2
    assert "'energy' names both a parameter and a results column" in capsys.readouterr().err


def test_the_model_identifier_is_a_c_name():
    from pathlib import Path

    from casmech.fmu.archive import identifier_of

    assert identifier_of(Path("out/my-arm v2.fmu")) == "my_arm_v2"
    assert identifier_of(Path("2link.fmu")) == "m_2link"
    assert identifier_of(Path("pendül.fmu")) == "pend_l"
