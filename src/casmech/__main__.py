"""`python -m casmech ARGS`: the same as the `casmech` command."""

import sys

from casmech.cli import main

if __name__ == "__main__":
    sys.exit(main())
