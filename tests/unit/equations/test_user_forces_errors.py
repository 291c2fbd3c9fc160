"""A force law naming the state wrongly, or the state named where it is not allowed: located
errors (file:line:col of the name inside the expression) with a hint, never a traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import casmech
import casmech.errors

BASE = """casmech: 1
name: errors
parameters: {k: 3.0}
bodies:
  - name: bar
    mass: MASS
    inertia: [0.3, 0.3, 0.5]
    position: [0, 0, 0]
  - name: block
    mass: 1
    inertia: [0.1, 0.1, 0.1]
    position: [1, 0, 0]
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 0, 1]}
  - {name: slide, type: translational, body_i: bar, body_j: block, at: [1, 0, 0],
     axis: [1, 0, 0]}
forces:
  - {name: law, type: torque, body: bar, value: [0, 0, "LAW"]}
"""
LAW_LINE = next(n for n, row in enumerate(BASE.splitlines(), 1) if "LAW" in row)
LAW_COL = BASE.splitlines()[LAW_LINE - 1].index("LAW") + 1


def diagnose(law: str = "-k*pivot.angle", mass: str = "1"):
    text = BASE.replace("LAW", law).replace("MASS", mass)
    with pytest.raises(casmech.errors.ModelError) as caught:
        casmech.loads(text, file="m.yaml")
    return caught.value.diagnostics


CASES = {  # law -> (name in it, words of the message, words of the hint)
    "-k*pivot.angel": ("pivot.angel", "revolute joint 'pivot' has no 'angel'",
                       "did you mean 'angle'?"),
    "-k*slide.angle": ("slide.angle", "translational joint 'slide' has no 'angle'",
                       "displacement, displacement_dot"),
    "-k*ground.x": ("ground.x", "'ground' does not move", "moving body"),
    "-k*bat.vx": ("bat.vx", "unknown state 'bat.vx'", "did you mean 'bar.vx'?"),
    "-k*bar.speed": ("bar.speed", "body 'bar' has no 'speed'", "vx, vy, vz"),
    "-k*pivot.angle_dot + k*piv.angle": ("piv.angle", "no body or joint 'piv'",
                                         "did you mean 'pivot.angle'?"),
}


@pytest.mark.parametrize("law", sorted(CASES))
def test_misnamed_state_is_located_with_a_hint(law):
    name, message, hint = CASES[law]
    (diagnostic,) = diagnose(law)
    assert diagnostic.code == "E201"
    assert message in diagnostic.message and hint in diagnostic.hint
    source = diagnostic.source
    assert (source.file, source.line, source.col) == ("m.yaml", LAW_LINE, LAW_COL + law.index(name))


def test_state_in_a_mass_is_not_allowed():
    (diagnostic,) = diagnose(mass="2 + bar.vx")
    assert diagnostic.code == "E201" and "'bar.vx' is not allowed here" in diagnostic.message
    assert "force/torque value, tsda/rsda actuator" in diagnostic.hint
    line = next(n for n, row in enumerate(BASE.splitlines(), 1) if "MASS" in row)
    assert (diagnostic.source.line, diagnostic.source.col) == (line, len("    mass: 2 + ") + 1)


@pytest.mark.parametrize("where", ["driver", "stiffness"])
def test_state_in_a_driver_or_a_coefficient_is_not_allowed(where):
    text = BASE.replace("LAW", "0").replace("MASS", "1")
    if where == "driver":
        text = text.replace("axis: [1, 0, 0]}", "axis: [1, 0, 0], driver: {displacement: "
                            "\"0.1*pivot.angle\"}}")
    else:
        text += "  - {name: s, type: rsda, joint: pivot, stiffness: \"k*pivot.angle\"}\n"
    with pytest.raises(casmech.errors.ModelError) as caught:
        casmech.loads(text)
    (diagnostic,) = caught.value.diagnostics
    assert diagnostic.code == "E201" and "'pivot.angle' is not allowed here" in diagnostic.message


def test_dotted_name_that_is_no_state_says_what_dotted_names_are():
    (diagnostic,) = diagnose(mass="leg.L")
    assert "unknown symbol 'leg.L'" in diagnostic.message and "<joint>.angle" in diagnostic.hint


def test_every_state_of_the_table_is_accepted():
    law = ("pivot.angle + pivot.angle_dot + slide.displacement + slide.displacement_dot"
           " + bar.x + bar.y + bar.z + bar.vx + bar.vy + bar.vz + bar.wx + bar.wy + block.wz + t")
    model = casmech.loads(BASE.replace("LAW", law).replace("MASS", "1"))
    assert model.forces[0].value[2].expr.symbols >= {"pivot.angle", "block.wz", "t"}


def test_check_command_prints_the_location_and_exits_1(tmp_path: Path):
    path = tmp_path / "m.yaml"
    path.write_text(BASE.replace("LAW", "-k*pivot.angel").replace("MASS", "1"))
    script = Path(sys.executable).parent / "casmech"
    done = subprocess.run([str(script), "check", str(path)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 1 and "Traceback" not in done.stderr
    where = f"m.yaml:{LAW_LINE}:{LAW_COL + 3}: error[E201]"
    assert where in done.stderr + done.stdout
