"""docs/cli.md against the parsers: every command has a section, every option of every parser
appears in its command's table, and the tables are what tests/cli_reference.py generates now
(regenerate with `python -m tests.cli_reference`)."""

import re

import pytest

from casmech import cli
from casmech.cli.commands import COMMANDS
from tests import cli_reference

TEXT = cli_reference.DOC.read_text(encoding="utf-8")
REGENERATE = "docs/cli.md is stale: run `python -m tests.cli_reference` and commit the result"


def block(command: str) -> str:
    match = next(m for m in cli_reference.BLOCK.finditer(TEXT) if m.group(2) == command)
    return match.group(3)


def test_every_command_has_a_section():
    assert sorted(cli_reference.documented(TEXT)) == sorted(COMMANDS)
    for command in COMMANDS:
        assert f"## casmech {command}\n" in TEXT


@pytest.mark.parametrize("command", list(COMMANDS))
def test_every_option_is_documented(command):
    table = block(command)
    actions = cli_reference.arguments(command)
    assert actions  # every command takes at least one argument
    for action in actions:
        names = action.option_strings or [action.dest]
        for name in names:
            assert f"`{name}`" in table, f"{command}: {name} is not in docs/cli.md"
        for choice in action.choices or ():
            assert f"`{choice}`" in table, f"{command} {names[0]}: choice {choice} missing"


def test_tables_are_up_to_date():
    assert cli_reference.generated(TEXT) == TEXT, REGENERATE


def test_top_level_options():
    parser, _ = cli._parser([])
    for action in parser._actions:
        for name in action.option_strings:
            assert re.search(rf"`{re.escape(name)}`", TEXT), name


def test_generator_sees_a_new_option(monkeypatch):
    """A parser change makes the generated text differ (the staleness test can fail)."""
    from casmech.cli import cache

    original = cache.add_arguments

    def more(parser):
        original(parser)
        parser.add_argument("--dry-run", action="store_true", help="say what would go")

    monkeypatch.setattr(cache, "add_arguments", more)
    assert "`--dry-run`" in cli_reference.table("cache")
    assert cli_reference.generated(TEXT) != TEXT
