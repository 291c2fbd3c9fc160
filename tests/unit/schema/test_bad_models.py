"""One bad model per diagnostic code, each reported with its code, path, line and column.

Every fixture's first line reads `# expect: CODE PATH LINE:COL` (`-` for an empty path).
"""

import re
from pathlib import Path

import pytest

from casmech.errors import CODES, ModelError
from casmech.schema import load_model, load_model_text

BAD_MODELS = Path(__file__).parent / "bad_models"
FIXTURES = sorted(BAD_MODELS.glob("*.yaml"))
EXPECT = re.compile(r"# expect: (E\d{3}) (\S+) (\d+):(\d+)$")


def expectation(path: Path) -> tuple[str, str, int, int]:
    match = EXPECT.match(path.read_text(encoding="utf-8").splitlines()[0])
    assert match, f"{path.name}: first line must be '# expect: CODE PATH LINE:COL'"
    code, where, line, col = match.groups()
    return code, "" if where == "-" else where, int(line), int(col)


def findings(text: str) -> list:
    with pytest.raises(ModelError) as caught:
        load_model_text(text, "m.yaml")
    return caught.value.diagnostics


@pytest.mark.parametrize("path", FIXTURES, ids=lambda path: path.stem)
def test_bad_model_is_reported_at_its_place(path):
    code, where, line, col = expectation(path)
    assert path.name.startswith(code)
    with pytest.raises(ModelError) as caught:
        load_model(path)
    found = [(d.code, d.path, d.source.line, d.source.col) for d in caught.value.diagnostics]
    assert found == [(code, where, line, col)]
    assert str(caught.value).startswith(f"{path}:{line}:{col}: error[{code}]")


def test_every_model_code_has_a_fixture():
    model_codes = {code for code in CODES if code[1] in "01234"}  # E5xx belong to the compiler
    assert {expectation(path)[0] for path in FIXTURES} == model_codes


MANY_STRUCTURAL = """\
casmech: 1
name: many
bodies:
  - name: bar
    mas: 1
    inertia: [1, 1, 1]
    position: [0, 0]
joints:
  - {name: pin, type: revolut, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 0, 1]}
analysis: {type: dynamic, t_end: 1}
"""

MANY_SEMANTIC = """\
casmech: 1
name: many
parameters:
  L: 2
  m: 3 * Lx
bodies:
  - name: bar
    mass: -1
    inertia: [1, 1, 5]
    position: [0, 0, t]
joints:
  - {name: pin, type: revolute, body_i: ground, body_j: barr, at: [0, 0, 0], axis: [0, 0, 0]}
  - {name: pin, type: spherical, body_i: ground, body_j: bar, at: [0, 0, 0]}
analysis: {t_end: -1}
"""


def test_structural_mistakes_are_reported_together():
    found = [(d.code, d.path) for d in findings(MANY_STRUCTURAL)]
    assert found == [
        ("E100", "bodies[0].mass"),
        ("E101", "bodies[0].mas"),
        ("E102", "bodies[0].position"),
        ("E103", "joints[0].type"),
        ("E103", "analysis.type"),
    ]


def test_semantic_mistakes_are_reported_together():
    found = [(d.code, d.path) for d in findings(MANY_SEMANTIC)]
    assert found == [
        ("E201", "parameters.m"),
        ("E400", "bodies[0].mass"),
        ("E402", "bodies[0].inertia"),
        ("E202", "bodies[0].position[2]"),
        ("E300", "joints[0].body_j"),
        ("E404", "joints[0].axis"),
        ("E301", "joints[1].name"),
        ("E409", "analysis.t_end"),
    ]


def test_did_you_mean_hints():
    hints = {(d.code, d.path): d.hint for d in findings(MANY_STRUCTURAL)}
    assert hints[("E101", "bodies[0].mas")] == "did you mean 'mass'?"
    assert hints[("E103", "joints[0].type")] == "did you mean 'revolute'?"
    assert hints[("E103", "analysis.type")] == "did you mean 'dynamics'?"
    hints = {(d.code, d.path): d.hint for d in findings(MANY_SEMANTIC)}
    assert hints[("E300", "joints[0].body_j")] == "did you mean 'bar'?"
    assert hints[("E201", "parameters.m")] == "did you mean 'L'?"


def test_rendering_has_expected_got_and_hint_lines():
    text = str(ModelError(findings(MANY_SEMANTIC)))
    assert "m.yaml:8:11: error[E400] bodies[0].mass: mass must be positive\n  got: -1" in text
    assert "m.yaml:5:10: error[E201] parameters.m: unknown symbol 'Lx'" in text
    assert "pydantic" not in text
