"""Diagnostics and error messages escape the control characters of what they echo (issue 35
item 4): an escape sequence in a name never reaches the terminal, and a newline in a name
cannot forge a diagnostic line of its own (errors.escape)."""

import re

from casmech.cli import main
from casmech.errors import AnalysisError, FailureContext, Source, UsageError, escape

FORGED = "file:1:1: error[E999] forged"
# a model whose names, name and keys carry a colour change, a window-title sequence, a
# carriage return, a right-to-left override and a newline followed by a forged diagnostic
MODEL = f"""casmech: 1
name: "evil\\e[31m"
bodies:
  - {{name: "b\\n{FORGED}", mass: 1, inertia: [1, 1, 1], position: [0, 0, 0]}}
  - {{name: "\\e]0;title\\a", mass: 1, inertia: [1, 1, 1], position: [0, 0, 0]}}
  - {{name: "c\\rd\\u202egnp.exe", mass: 1, inertia: [1, 1, 1], position: [0, 0, 0]}}
joints:
  - {{name: "j\\e[2J", type: revolute, body_i: ground, body_j: "b\\n{FORGED}", at: [0, 0, 0],
     axis: [0, 0, 1]}}
"key\\e[2J": 1
"""
CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e]")


def test_check_echoes_no_control_character_and_no_forged_line(tmp_path, capsys):
    path = tmp_path / "evil.yaml"
    path.write_text(MODEL)
    assert main(["check", str(path)]) == 1
    err = capsys.readouterr().err
    assert err.strip(), "check reported nothing"
    assert not CONTROL.search(err), repr(err)
    assert not any(line.startswith(FORGED) for line in err.splitlines()), err
    assert "\\x1b[2J" in err  # the key is still named, escaped
    lines = err.strip().splitlines()
    # every line is a located diagnostic of this file or an indented detail
    assert all(line.startswith((f"{path}:", "  ")) for line in lines), err


def test_escape_writes_each_control_character_as_its_escape():
    assert escape("a\x1b[31mb") == "a\\x1b[31mb"
    assert escape(f"x\n{FORGED}") == f"x\\n{FORGED}"
    assert escape("\r\t\x07\x7f\x9b\u202e\u2066") == "\\r\\t\\x07\\x7f\\x9b\\u202e\\u2066"
    assert escape("Gelenk_ä φ 関節 ok") == "Gelenk_ä φ 関節 ok"  # printable text stays
    assert escape("one\ntwo\x1b", keep_newlines=True) == "one\ntwo\\x1b"


def test_error_messages_escape_what_they_echo():
    context = FailureContext(0.5, "singular\x1b[2J", [(f"j\n{FORGED}", Source("m\x1b.yaml", 3, 1),
                                                      1.0)])
    text = str(AnalysisError(context))
    assert not CONTROL.search(text)
    assert not any(line.startswith(FORGED) for line in text.splitlines())
    assert "m\\x1b.yaml:3:1: joint 'j\\nfile:1:1: error[E999] forged'" in text
    usage = str(UsageError("first line\nsecond \x1b[31mline"))
    assert usage == "first line\nsecond \\x1b[31mline"


def test_the_patterns_are_compiled_when_first_used():
    """Importing casmech.errors compiles neither of its patterns (a run that ends well uses
    none); the first escape compiles the control characters' once, and every control
    character of the set (and no other) is escaped."""
    import subprocess
    import sys

    probe = ("from casmech import errors\n"
             "assert errors._pattern.cache_info().currsize == 0\n"
             "assert errors.escape('a\\x1bb\\u202ec\\u2028') == 'a\\\\x1bb\\\\u202ec\\\\u2028'\n"
             "assert errors._pattern.cache_info().currsize == 1\n")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    every = "".join(map(chr, range(0x3000)))
    kept = "".join(c for c in every if escape(c) == c)
    assert kept == re.sub("[\x00-\x1f\x7f-\x9f\u200e\u200f\u202a-\u202e\u2066-\u2069\u2028"
                          "\u2029]", "", every)
