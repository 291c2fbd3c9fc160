"""casmech command line: parse arguments, call the API, render diagnostics.

Each subcommand is a module of casmech.cli (listed in cli.commands.COMMANDS). Only the module
of the command on the command line is imported, so each command pays for its own imports
(`casmech --help` imports none; docs/decisions/lazy-imports.md).
Exit codes (docs/format.md): 0 success, 1 model error, 2 usage error, 3 analysis failure,
130/143 stopped by SIGINT/SIGTERM.
"""

from __future__ import annotations

import argparse
import atexit
import contextlib
import importlib
import os
import sys

# One BLAS thread unless the user chose: casmech's dense linear algebra is on small matrices,
# where OpenBLAS's threads cost more than they gain on a busy machine
# (docs/decisions/one-blas-thread.md).
# Set before a command imports NumPy.
for _variable in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

# No pydantic plugins unless the user chose: looking for them reads the entry points of every
# installed distribution when the model's validator is built, after importing
# importlib.metadata (docs/decisions/pydantic-plugins.md).
os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")

from casmech.cli import collector  # noqa: E402
from casmech.cli.commands import COMMANDS  # noqa: E402
from casmech.core.version import VERSION  # noqa: E402
from casmech.errors import (  # noqa: E402
    CasmechError,
    Interrupted,
    ModelError,
    Source,
    UsageError,
)

DESCRIPTION = "casmech: a declarative compiler for 3D rigid multibody mechanisms on CasADi."


def chosen(argv: list[str]) -> str | None:
    """The command named on the command line: the first argument that is not an option (no
    option before the command takes a value)."""
    return next((arg for arg in argv if not arg.startswith("-")), None)


def _parser(argv: list[str]) -> tuple[argparse.ArgumentParser, object | None]:
    """The parser, with the arguments of the chosen command only, and that command's module."""
    parser = argparse.ArgumentParser(prog="casmech", description=DESCRIPTION)
    parser.add_argument("--version", action="version", version=f"casmech {VERSION}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    name = chosen(argv)
    # a command given first (`casmech run ...`) is parsed by its own parser alone, and no
    # message of the parse names the others: only its parser is made then
    alone = bool(argv) and argv[0] == name and name in COMMANDS
    module = None
    for command, (module_name, help_text) in COMMANDS.items():
        if alone and command != name:
            continue
        sub = commands.add_parser(command, help=help_text, description=help_text)
        if command == name:
            module = importlib.import_module(f"casmech.cli.{module_name}")
            module.add_arguments(sub)
    return parser, module


def main(argv: list[str] | None = None) -> int:
    """The command line; `argv` None: this process's own (then its garbage collector waits
    until the command's long part, cli.collector; a command a signal stopped ends at once,
    its files written: see _end; and a command that asks, `run`, ends the process as it
    returns: see _leave)."""
    own = argv is None
    if own:
        collector.hold()
    argv = sys.argv[1:] if argv is None else list(argv)
    parser, module = _parser(argv)
    args = parser.parse_args(argv)
    if not getattr(module, "RELEASES_COLLECTOR", False):  # (run: when its analysis starts)
        collector.release()
    code = _command(module, args, own)
    if own and getattr(module, "ENDS_AT_ONCE", False):
        _leave(code)  # (returns where the interpreter's own exit is needed)
    return code


def _command(module, args, own: bool) -> int:
    """The command's exit code, its errors rendered."""
    try:
        return module.run(args)
    except ModelError as error:
        print(error.format(), file=sys.stderr)
        return error.exit_code
    except Interrupted as error:
        print(f"casmech: {error}", file=sys.stderr)
        return _end(error.exit_code) if own else error.exit_code
    except CasmechError as error:
        print(f"casmech: {error}", file=sys.stderr)
        return error.exit_code
    except FileNotFoundError as error:
        print(f"casmech: {Source(str(error.filename), 1, 1)}: no such file", file=sys.stderr)
        return UsageError.exit_code
    except KeyboardInterrupt:  # Ctrl-C in a command that keeps nothing (run: errors.Interrupted)
        print("casmech: interrupted", file=sys.stderr)
        return 130
    finally:
        if own:
            collector.end()


def _leave(code: int) -> None:
    """End the process with `code` without the interpreter's teardown, as it would end
    otherwise: the atexit handlers run (weakref finalizers, logging, a coverage tool's), then
    C's and Python's standard streams are flushed. Returns, leaving the exit to the
    interpreter, where that is not all it would do: while a thread the interpreter would wait
    for is alive, or when a stream cannot be flushed (the interpreter reports that itself)."""
    threading = sys.modules.get("threading")
    if threading is not None and any(
            not thread.daemon and thread is not threading.main_thread()
            for thread in threading.enumerate()):
        return
    atexit._run_exitfuncs()
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except (OSError, ValueError):  # (a closed pipe, a closed stream)
        return
    _flush_c_streams()
    os._exit(code)


def _flush_c_streams() -> None:
    """fflush(NULL): what a library wrote through C's stdio and left in its buffers (a pipe's
    stdout is fully buffered), flushed as C's exit would flush it."""
    ctypes = sys.modules.get("ctypes")  # (NumPy and CasADi import it; else nothing wrote)
    if ctypes is not None:
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None).fflush(None)


def _end(code: int) -> int:
    """End the process now with `code`: a command a signal stopped has written its files
    (closed, or replaced whole), and the interpreter's teardown of the modules it loaded
    (CasADi, SciPy: a few tenths of a second) would only delay the stop the user asked for."""
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
