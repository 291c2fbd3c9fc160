"""casmech.study.block: a YAML `study:` block's mistakes as located errors, the command line's
as usage errors."""

import pytest

import casmech
from casmech.errors import ModelError
from tests.helpers.study import PENDULUM

BASE = PENDULUM.read_text().split("study:")[0]
LINES = BASE.count("\n")  # the block's first line is LINES + 1


def located(tmp_path, block: str) -> str:
    path = tmp_path / "model.yaml"
    path.write_text(BASE + block)
    with pytest.raises(ModelError) as error:
        casmech.sweep(path, workers=0)
    return error.value.format()


@pytest.mark.parametrize("block, line, col, text", [
    ('study:\n  grid: {Lx: "1,2"}\n', 2, 10, "error[E300] study.grid.Lx: unknown parameter 'Lx'"
                                            "\n  hint: did you mean 'L'?"),
    ('study:\n  grid: {bob: "1,2"}\n', 2, 10, "error[E300] study.grid.bob: 'bob' is a body, "
                                             "not a parameter"),
    ('study:\n  grid:\n    L: "1:2:0"\n', 3, 8, "error[E409] study.grid.L: range '1:2:0': COUNT"),
    ('study:\n  grid:\n    L: "1:2"\n', 3, 8, "error[E103] study.grid.L: range '1:2' is not "
                                             "START:STOP:COUNT"),
    ('study:\n  samples: 5\n  normal:\n    m: [1, -0.1]\n', 4, 8,
     "error[E409] study.normal.m: normal: the standard deviation -0.1 is negative"),
    ('study:\n  grid: {L: [1]}\n  keep: ["max(bob.zz)"]\n', 3, 10,
     "error[E300] study.keep[0]: kept output 'max(bob.zz)': no results column 'bob.zz'"),
])
def test_located(tmp_path, block, line, col, text):
    message = located(tmp_path, block)
    where = f"{tmp_path / 'model.yaml'}:{LINES + line}:{col}"
    assert message.startswith(f"{where}: {text}"), message


def test_every_problem_at_once(tmp_path):
    message = located(tmp_path, 'study:\n  grid: {Lx: "1,2", m: "1:2:x"}\n')
    assert "E300" in message and "E409" in message


def test_schema_types_are_model_errors(tmp_path):
    """A wrong type is found by the format's schema when the model loads (E102)."""
    message = located(tmp_path, "study:\n  samples: many\n")
    assert "error[E102] study.samples" in message, message


def test_command_line_replaces_the_block_and_says_which_option():
    with pytest.raises(casmech.UsageError) as error:
        casmech.sweep(PENDULUM, grid={"Lx": [1.0]}, workers=0)
    assert str(error.value) == ("error[E300] --grid Lx: unknown parameter 'Lx' "
                                "(did you mean 'L'?)")
    table = casmech.sweep(PENDULUM, grid={"m": [2.0]}, workers=0)  # the block's grid replaced
    assert list(table.columns[:3]) == ["run", "m", "status"]
    assert list(table.columns[4:]) == ["crossing(bob.y)", "reason"]  # the block's keep kept
