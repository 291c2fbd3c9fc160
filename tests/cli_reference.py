"""The option tables of docs/cli.md, generated from casmech's argparse parsers.

    python -m tests.cli_reference        # rewrite the tables in docs/cli.md

Each command's table sits between `<!-- options: casmech COMMAND -->` and `<!-- end options -->`;
the text around them is written by hand. tests/integration/test_cli_docs.py fails when a table
differs from what the parsers say now (an option added, renamed, its help or choices changed).
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from casmech import cli
from casmech.cli.commands import COMMANDS

DOC = Path(__file__).resolve().parents[1] / "docs" / "cli.md"
BLOCK = re.compile(r"(<!-- options: casmech (\S+) -->\n)(.*?)(<!-- end options -->)", re.S)
HEADER = ("| argument | value | default | what |\n"
          "|---|---|---|---|\n")


def subparser(command: str) -> argparse.ArgumentParser:
    """The parser of one command, with its arguments (cli adds only the chosen command's)."""
    parser, _ = cli._parser([command])
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[command]


def arguments(command: str) -> list[argparse.Action]:
    """The command's arguments but -h/--help."""
    return [action for action in subparser(command)._actions
            if not isinstance(action, argparse._HelpAction)]


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def _value(action: argparse.Action) -> str:
    if action.nargs == 0:
        return ""
    if action.metavar is not None:
        return f"`{_cell(action.metavar)}`"
    if action.choices is not None:
        return " \\| ".join(f"`{_cell(choice)}`" for choice in action.choices)
    return f"`{action.dest.upper()}`" if action.option_strings else ""


def _default(action: argparse.Action) -> str:
    if action.nargs == 0 or action.default in (None, [], argparse.SUPPRESS):
        return ""
    default = action.default
    return f"`{', '.join(default) if isinstance(default, list) else default}`"


def _name(action: argparse.Action) -> str:
    names = action.option_strings or [action.dest]
    suffix = " ..." if action.nargs in ("*", "+") else (" (optional)" if action.nargs == "?"
                                                       else "")
    return ", ".join(f"`{name}`" for name in names) + suffix


def table(command: str) -> str:
    rows = [f"| {_name(a)} | {_value(a)} | {_default(a)} | {_cell(a.help or '')} |\n"
            for a in arguments(command)]
    return "\n" + HEADER + "".join(rows) + "\n"


def generated(text: str) -> str:
    """`text` with every command's table as the parsers give it now."""
    return BLOCK.sub(lambda m: m.group(1) + table(m.group(2)) + m.group(4), text)


def documented(text: str) -> list[str]:
    return [match.group(2) for match in BLOCK.finditer(text)]


def main() -> int:
    text = DOC.read_text(encoding="utf-8")
    missing = [command for command in COMMANDS if command not in documented(text)]
    if missing:
        print(f"docs/cli.md has no section for {', '.join(missing)}: add a heading, a few "
              "lines and an empty `<!-- options: casmech COMMAND -->` / `<!-- end options -->` "
              "pair, then run this again", file=sys.stderr)
        return 1
    DOC.write_text(generated(text), encoding="utf-8")
    print(f"wrote {DOC}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
