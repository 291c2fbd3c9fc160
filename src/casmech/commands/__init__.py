"""The subcommands of `casmech`, one module each.

COMMANDS maps a command's name to its module in this package; every module defines HELP (one
line), add_arguments(parser) and run(args) -> int (the exit code). cli.py builds the parser from
this table: a new command is a new module and one new entry here.
"""

COMMANDS = {
    "check": "check",
    "run": "run",
    "sensitivity": "sensitivity",
    "optimize": "optimize",
    "compile": "compile",
    "cache": "cache",
    "plot": "plot",
    "inspect": "inspect",
    "import": "import_cmd",
    "animate": "animate",
}
