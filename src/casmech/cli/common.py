"""Argument helpers shared by several subcommands."""

from __future__ import annotations

import argparse

from casmech.errors import UsageError


class _AllowDir(argparse.Action):
    """--allow-dir DIR: the model may name files under DIR too (casmech.schema.files)."""

    def __call__(self, parser, namespace, value, option_string=None) -> None:
        from casmech.schema import files

        files.allow(value)
        getattr(namespace, self.dest).append(value)


def add_span(parser: argparse.ArgumentParser) -> None:
    """--t-end, --output-step, --rtol, --atol: the analysis settings a run or a study
    overrides."""
    parser.add_argument("--t-end", type=float, help="end time [s]")
    parser.add_argument("--output-step", type=float, help="output interval [s]")
    parser.add_argument("--rtol", type=float,
                        help="relative tolerance of the integrator (dynamics)")
    parser.add_argument("--atol", type=float,
                        help="absolute tolerance of the integrator (dynamics)")


def add_overrides(parser: argparse.ArgumentParser) -> None:
    """--set NAME=VALUE and --allow-dir DIR: options of every command that loads a model."""
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="override a parameter (repeatable)")
    parser.add_argument("--allow-dir", action=_AllowDir, default=[], metavar="DIR",
                        help="a folder outside the model's own from which it may read tables, "
                             "component files, meshes and data (repeatable; also "
                             "$CASMECH_ALLOWED_DIRS)")


def overrides(pairs: list[str]) -> dict[str, str]:
    """--set NAME=VALUE pairs as a mapping (a usage error for anything else)."""
    result = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise UsageError(f"--set expects NAME=VALUE, got '{pair}'")
        result[name.strip()] = value.strip()
    return result


def add_options(parser: argparse.ArgumentParser) -> None:
    """--option KEY=VALUE: an option of the analysis type (docs/analyses.md#options)."""
    parser.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                        help="an option of the analysis, e.g. max_step=1e-3 or "
                             "assembly.tolerance=1e-10; a key under solver: may leave out "
                             "'solver.' (repeatable; docs/analyses.md#options)")


def options(pairs: list[str]) -> dict[str, str]:
    """--option KEY=VALUE pairs as a mapping of texts (checked against the analysis type's
    options by casmech.analyze; a usage error here for anything not KEY=VALUE)."""
    result = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise UsageError(f"--option expects KEY=VALUE (e.g. max_step=1e-3), got '{pair}'")
        if key.strip() in result:
            raise UsageError(f"--option {key.strip()} is given twice")
        result[key.strip()] = value.strip()
    return result
