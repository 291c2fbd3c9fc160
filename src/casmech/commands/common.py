"""Argument helpers shared by several subcommands."""

from __future__ import annotations

import argparse

from casmech.errors import UsageError


def add_overrides(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="override a parameter (repeatable)")


def overrides(pairs: list[str]) -> dict[str, str]:
    """--set NAME=VALUE pairs as a mapping (a usage error for anything else)."""
    result = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise UsageError(f"--set expects NAME=VALUE, got '{pair}'")
        result[name.strip()] = value.strip()
    return result
