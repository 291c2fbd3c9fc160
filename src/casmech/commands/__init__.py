"""The subcommands of `casmech`, one module each.

Every module listed in NAMES defines HELP (one line), add_arguments(parser) and run(args) -> int
(the exit code). cli.py builds the parser from this table; a new command is a new module and one
new name here.
"""

NAMES = ("check", "run")
