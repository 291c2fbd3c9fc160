"""casmech command line: parse arguments, call the API, render diagnostics.

Each subcommand is a module of casmech.commands (listed in commands.COMMANDS).
Exit codes (MODEL_FORMAT.md): 0 success, 1 model error, 2 usage error, 3 analysis failure.
"""

from __future__ import annotations

import argparse
import importlib
import sys

import casmech
from casmech.commands import COMMANDS
from casmech.errors import CasmechError, ModelError, Source, UsageError


def _modules() -> dict:
    return {name: importlib.import_module(f"casmech.commands.{module}")
            for name, module in COMMANDS.items()}


def _parser(modules: dict) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="casmech", description=casmech.__doc__)
    parser.add_argument("--version", action="version", version=f"casmech {casmech.__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, module in modules.items():
        module.add_arguments(commands.add_parser(name, help=module.HELP))
    return parser


def main(argv: list[str] | None = None) -> int:
    modules = _modules()
    args = _parser(modules).parse_args(argv)
    try:
        return modules[args.command].run(args)
    except ModelError as error:
        print(error.format(), file=sys.stderr)
        return error.exit_code
    except CasmechError as error:
        print(f"casmech: {error}", file=sys.stderr)
        return error.exit_code
    except FileNotFoundError as error:
        print(f"casmech: {Source(str(error.filename), 1, 1)}: no such file", file=sys.stderr)
        return UsageError.exit_code


if __name__ == "__main__":
    sys.exit(main())
